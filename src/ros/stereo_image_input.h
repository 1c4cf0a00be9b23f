#pragma once

// The StereoTracker's camera input: left and right images through image_transport, paired by
// message_filters (ExactTime, or ApproximateTime with ~approximate_sync), and on request the
// camera_info beside each image topic; and where the camera sits on the robot (the calibration
// file or the camera_info, and ~base_to_camera).

#include <functional>
#include <memory>
#include <optional>
#include <string>

#include <image_transport/image_transport.h>
#include <image_transport/subscriber_filter.h>
#include <message_filters/subscriber.h>
#include <message_filters/sync_policies/approximate_time.h>
#include <message_filters/sync_policies/exact_time.h>
#include <message_filters/synchronizer.h>
#include <ros/node_handle.h>
#include <sensor_msgs/CameraInfo.h>
#include <sensor_msgs/Image.h>
#include <Eigen/Geometry>

#include "stereo_fabmap_slam/camera/stereo_rectifier.h"

namespace stereo_fabmap_slam::ros_input {

// The rectified stereo rig and where its rectified left camera sits on the base.
struct MountedRig {
  camera::StereoRectifier rectifier;
  Eigen::Isometry3d T_base_camera = Eigen::Isometry3d::Identity();
};

// ~base_to_camera [x, y, z, qx, qy, qz, qw]: the raw left camera in the base frame, if set.
// Throws std::invalid_argument for a list that is not 7 numbers or a quaternion of zero length.
std::optional<Eigen::Isometry3d> ReadBaseToCamera(const ros::NodeHandle& private_node);

// From a calibration file (camera::ReadStereoCalibrationYaml): its body is the base unless it
// says where the base is (T_body_base); `base_to_camera` places the raw left camera on the base
// instead (both cameras move; the stereo extrinsic stays). Throws for a bad file.
MountedRig RigFromCalibrationFile(const std::string& path,
                                  const camera::RectificationOptions& options,
                                  const std::optional<Eigen::Isometry3d>& base_to_camera);
// From a camera_info pair, which says nothing of the mounting: the raw left camera is
// `base_to_camera` in the base, or the base itself. Throws std::invalid_argument.
MountedRig RigFromCameraInfo(const sensor_msgs::CameraInfo& left,
                             const sensor_msgs::CameraInfo& right,
                             const std::optional<Eigen::Isometry3d>& base_to_camera);

class StereoImageInput {
 public:
  using Image = sensor_msgs::ImageConstPtr;
  using Info = sensor_msgs::CameraInfoConstPtr;
  using PairCallback = std::function<void(const Image& left, const Image& right)>;
  using ImageCallback = std::function<void(int side)>;  // 0 left, 1 right
  using InfoCallback = std::function<void(const Info& left, const Info& right)>;

  // Subscribes left/image_raw and right/image_raw of `node` (~image_transport picks the
  // transport). `on_pair` gets each synchronised pair, `on_image` each image of one side first.
  StereoImageInput(ros::NodeHandle& node, const ros::NodeHandle& private_node, int queue_size,
                   bool approximate, PairCallback on_pair, ImageCallback on_image);
  // Unsubscribes first, which waits for an image callback in progress (roscpp removes a
  // subscription's callbacks under their calling lock): members go in reverse order, the
  // synchronisers before the subscribers that feed them, so a callback still running would
  // reach a destroyed synchroniser and lock its destroyed mutex. (A launch that unloaded the
  // StereoTracker ended once in "terminate called ... boost::lock_error", in the load rostest
  // of a fresh-clone make test; the next run of the same code passed.)
  ~StereoImageInput();
  StereoImageInput(const StereoImageInput&) = delete;
  StereoImageInput& operator=(const StereoImageInput&) = delete;
  // The camera_info of each image topic (left/camera_info beside left/image_raw: one remap of
  // the image moves both, as image_transport's CameraSubscriber does), paired by stamp.
  void SubscribeCameraInfo(ros::NodeHandle& node, int queue_size, InfoCallback on_info);

  std::string Describe() const;  // the topics, for the log

 private:
  using ExactPolicy =
      message_filters::sync_policies::ExactTime<sensor_msgs::Image, sensor_msgs::Image>;
  using ApproximatePolicy =
      message_filters::sync_policies::ApproximateTime<sensor_msgs::Image, sensor_msgs::Image>;
  using InfoPolicy =
      message_filters::sync_policies::ExactTime<sensor_msgs::CameraInfo, sensor_msgs::CameraInfo>;

  void OnPair(const Image& left, const Image& right) { on_pair_(left, right); }
  void OnInfo(const Info& left, const Info& right) { on_info_(left, right); }

  bool approximate_;
  PairCallback on_pair_;
  InfoCallback on_info_;
  image_transport::ImageTransport transport_;
  image_transport::SubscriberFilter left_, right_;
  message_filters::Subscriber<sensor_msgs::CameraInfo> left_info_, right_info_;
  std::unique_ptr<message_filters::Synchronizer<ExactPolicy>> exact_sync_;
  std::unique_ptr<message_filters::Synchronizer<ApproximatePolicy>> approximate_sync_;
  std::unique_ptr<message_filters::Synchronizer<InfoPolicy>> info_sync_;
};

}  // namespace stereo_fabmap_slam::ros_input
