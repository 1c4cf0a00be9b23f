#include "stereo_image_input.h"

#include <stdexcept>
#include <vector>

#include <image_transport/camera_common.h>

#include "ros_conversions.h"
#include "stereo_fabmap_slam/camera/camera_calibration.h"

namespace stereo_fabmap_slam::ros_input {

std::optional<Eigen::Isometry3d> ReadBaseToCamera(const ros::NodeHandle& private_node) {
  std::vector<double> mount;
  if (!private_node.getParam("base_to_camera", mount)) return std::nullopt;
  if (mount.size() != 7) {
    throw std::invalid_argument("~base_to_camera needs 7 numbers [x, y, z, qx, qy, qz, qw], got " +
                                std::to_string(mount.size()));
  }
  const Eigen::Quaterniond rotation(mount[6], mount[3], mount[4], mount[5]);
  if (rotation.norm() < 1e-6) {
    throw std::invalid_argument("~base_to_camera: the quaternion has zero length");
  }
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear() = rotation.normalized().toRotationMatrix();
  T.translation() = Eigen::Vector3d(mount[0], mount[1], mount[2]);
  return T;
}

MountedRig RigFromCalibrationFile(const std::string& path,
                                  const camera::RectificationOptions& options,
                                  const std::optional<Eigen::Isometry3d>& base_to_camera) {
  camera::StereoCalibration calibration = camera::ReadStereoCalibrationYaml(path);
  Eigen::Isometry3d T_base_body = calibration.T_body_base.inverse();
  if (base_to_camera) {
    // Move both cameras so that the left one sits at the given mounting.
    const Eigen::Isometry3d move = *base_to_camera * calibration.left.T_body_camera.inverse();
    calibration.left.T_body_camera = move * calibration.left.T_body_camera;
    calibration.right.T_body_camera = move * calibration.right.T_body_camera;
    T_base_body = Eigen::Isometry3d::Identity();
  }
  MountedRig rig{camera::StereoRectifier::FromCalibration(calibration, options)};
  rig.T_base_camera = T_base_body * rig.rectifier.T_body_rectified_left();
  return rig;
}

MountedRig RigFromCameraInfo(const sensor_msgs::CameraInfo& left,
                             const sensor_msgs::CameraInfo& right,
                             const std::optional<Eigen::Isometry3d>& base_to_camera) {
  MountedRig rig{ros_conversions::RectifierFromCameraInfo(
      left, right, base_to_camera.value_or(Eigen::Isometry3d::Identity()))};
  rig.T_base_camera = rig.rectifier.T_body_rectified_left();
  return rig;
}

StereoImageInput::~StereoImageInput() {
  left_.unsubscribe();
  right_.unsubscribe();
  left_info_.unsubscribe();
  right_info_.unsubscribe();
}

StereoImageInput::StereoImageInput(ros::NodeHandle& node, const ros::NodeHandle& private_node,
                                   int queue_size, bool approximate, PairCallback on_pair,
                                   ImageCallback on_image)
    : approximate_(approximate), on_pair_(std::move(on_pair)), transport_(node) {
  const image_transport::TransportHints hints("raw", ros::TransportHints(), private_node);
  left_.subscribe(transport_, "left/image_raw", queue_size, hints);
  right_.subscribe(transport_, "right/image_raw", queue_size, hints);
  // Before the synchroniser's: each image is counted before its pair forms.
  left_.registerCallback([on_image](const Image&) { on_image(0); });
  right_.registerCallback([on_image](const Image&) { on_image(1); });
  if (approximate) {
    approximate_sync_ = std::make_unique<message_filters::Synchronizer<ApproximatePolicy>>(
        ApproximatePolicy(queue_size), left_, right_);
    approximate_sync_->registerCallback(&StereoImageInput::OnPair, this);
  } else {
    exact_sync_ = std::make_unique<message_filters::Synchronizer<ExactPolicy>>(
        ExactPolicy(queue_size), left_, right_);
    exact_sync_->registerCallback(&StereoImageInput::OnPair, this);
  }
}

void StereoImageInput::SubscribeCameraInfo(ros::NodeHandle& node, int queue_size,
                                           InfoCallback on_info) {
  left_info_.subscribe(
      node, image_transport::getCameraInfoTopic(node.resolveName("left/image_raw")), queue_size);
  right_info_.subscribe(
      node, image_transport::getCameraInfoTopic(node.resolveName("right/image_raw")), queue_size);
  on_info_ = std::move(on_info);
  info_sync_ = std::make_unique<message_filters::Synchronizer<InfoPolicy>>(InfoPolicy(queue_size),
                                                                           left_info_, right_info_);
  info_sync_->registerCallback(&StereoImageInput::OnInfo, this);
}

std::string StereoImageInput::Describe() const {
  std::string text = left_.getTopic() + " + " + right_.getTopic() +
                     (approximate_ ? " (approximate" : " (exact") + " time sync)";
  if (info_sync_) {
    text += ", calibration from " + left_info_.getTopic() + " + " + right_info_.getTopic();
  }
  return text;
}

}  // namespace stereo_fabmap_slam::ros_input
