#include "ros_conversions.h"

#include <stdexcept>

#include <cv_bridge/cv_bridge.h>
#include <sensor_msgs/image_encodings.h>
#include <tf2_eigen/tf2_eigen.h>

namespace stereo_fabmap_slam::ros_conversions {

ros::Time ToRosTime(std::int64_t timestamp_ns) {
  ros::Time time;
  time.fromNSec(static_cast<std::uint64_t>(timestamp_ns));
  return time;
}

std::int64_t ToNanoseconds(const ros::Time& time) {
  return static_cast<std::int64_t>(time.toNSec());
}

sensor_msgs::ImagePtr ToMono8ImageMessage(const cv::Mat& image, const ros::Time& stamp,
                                          const std::string& frame_id) {
  if (image.type() != CV_8UC1) throw std::invalid_argument("expected a mono8 (CV_8UC1) image");
  std_msgs::Header header;
  header.stamp = stamp;
  header.frame_id = frame_id;
  return cv_bridge::CvImage(header, sensor_msgs::image_encodings::MONO8, image).toImageMsg();
}

geometry_msgs::Pose ToPoseMessage(const Eigen::Isometry3d& pose) { return tf2::toMsg(pose); }

Eigen::Isometry3d FromPoseMessage(const geometry_msgs::Pose& pose) {
  Eigen::Isometry3d result;
  tf2::fromMsg(pose, result);
  return result;
}

camera::RectificationParameters FromCameraInfo(const sensor_msgs::CameraInfo& info) {
  if (info.distortion_model != "plumb_bob" || (info.D.size() != 4 && info.D.size() != 5)) {
    throw std::invalid_argument(
        "CameraInfo: only the plumb_bob model with 4 or 5 coefficients "
        "is supported, got '" +
        info.distortion_model + "' with " + std::to_string(info.D.size()));
  }
  camera::RectificationParameters parameters;
  parameters.size = cv::Size(static_cast<int>(info.width), static_cast<int>(info.height));
  for (int i = 0; i < 9; ++i) {
    parameters.K.val[i] = info.K[i];
    parameters.R.val[i] = info.R[i];
  }
  for (int i = 0; i < 12; ++i) parameters.P.val[i] = info.P[i];
  parameters.D.assign(info.D.begin(), info.D.end());
  return parameters;
}

sensor_msgs::CameraInfo ToCameraInfo(const camera::RectificationParameters& parameters,
                                     const std::string& frame_id) {
  sensor_msgs::CameraInfo info;
  info.header.frame_id = frame_id;
  info.width = static_cast<std::uint32_t>(parameters.size.width);
  info.height = static_cast<std::uint32_t>(parameters.size.height);
  info.distortion_model = "plumb_bob";
  info.D.assign(parameters.D.begin(), parameters.D.end());
  for (int i = 0; i < 9; ++i) {
    info.K[i] = parameters.K.val[i];
    info.R[i] = parameters.R.val[i];
  }
  for (int i = 0; i < 12; ++i) info.P[i] = parameters.P.val[i];
  return info;
}

camera::StereoRectifier RectifierFromCameraInfo(const sensor_msgs::CameraInfo& left,
                                                const sensor_msgs::CameraInfo& right,
                                                const Eigen::Isometry3d& T_body_left_raw) {
  return camera::StereoRectifier::FromParameters(FromCameraInfo(left), FromCameraInfo(right),
                                                 T_body_left_raw);
}

}  // namespace stereo_fabmap_slam::ros_conversions
