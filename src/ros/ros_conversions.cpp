#include "ros_conversions.h"

#include <cstring>
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

stereo_fabmap_slam::Keyframe ToKeyframeMessage(const map::Keyframe& keyframe,
                                               const geometry::StereoCamera& camera,
                                               const std::string& frame_id) {
  stereo_fabmap_slam::Keyframe message;
  message.header.stamp.fromSec(keyframe.timestamp);
  message.header.frame_id = frame_id;
  message.id = static_cast<std::uint64_t>(keyframe.id);
  message.starts_new_map = keyframe.starts_new_map;
  message.pose = ToPoseMessage(keyframe.T_world_camera);
  message.fx = camera.fx;
  message.fy = camera.fy;
  message.cx = camera.cx;
  message.cy = camera.cy;
  message.baseline = camera.baseline;
  message.width = static_cast<std::uint32_t>(camera.size.width);
  message.height = static_cast<std::uint32_t>(camera.size.height);
  const features::StereoFeatures& f = keyframe.features;
  const std::size_t n = f.size();
  message.u.resize(n);
  message.v.resize(n);
  message.u_right.assign(f.u_right.begin(), f.u_right.end());
  message.points.resize(n);
  for (std::size_t i = 0; i < n; ++i) {
    message.u[i] = f.keypoints[i].pt.x;
    message.v[i] = f.keypoints[i].pt.y;
    message.points[i].x = static_cast<float>(f.points[i].x());
    message.points[i].y = static_cast<float>(f.points[i].y());
    message.points[i].z = static_cast<float>(f.points[i].z());
  }
  const cv::Mat descriptors = f.descriptors.isContinuous() ? f.descriptors : f.descriptors.clone();
  message.descriptors_are_float = descriptors.type() == CV_32F;
  message.descriptor_bytes = static_cast<std::uint32_t>(descriptors.cols * descriptors.elemSize());
  message.descriptors.assign(descriptors.data,
                             descriptors.data + descriptors.total() * descriptors.elemSize());
  message.map_point_ids.assign(keyframe.map_point_ids.begin(), keyframe.map_point_ids.end());
  return message;
}

map::Keyframe FromKeyframeMessage(const stereo_fabmap_slam::Keyframe& message) {
  const std::size_t n = message.u.size();
  if (message.v.size() != n || message.u_right.size() != n || message.points.size() != n ||
      message.map_point_ids.size() != n ||
      message.descriptors.size() != n * message.descriptor_bytes) {
    throw std::invalid_argument("Keyframe message: arrays of different lengths");
  }
  map::Keyframe keyframe;
  keyframe.id = static_cast<std::int64_t>(message.id);
  keyframe.timestamp = message.header.stamp.toSec();
  keyframe.T_world_camera = FromPoseMessage(message.pose);
  keyframe.starts_new_map = message.starts_new_map;
  features::StereoFeatures& f = keyframe.features;
  f.keypoints.resize(n);
  f.points.resize(n);
  f.u_right.assign(message.u_right.begin(), message.u_right.end());
  for (std::size_t i = 0; i < n; ++i) {
    f.keypoints[i] = cv::KeyPoint(message.u[i], message.v[i], 7.0f);
    f.points[i] = Eigen::Vector3d(message.points[i].x, message.points[i].y, message.points[i].z);
  }
  const int element = message.descriptors_are_float ? CV_32F : CV_8U;
  const int columns =
      static_cast<int>(message.descriptor_bytes / (message.descriptors_are_float ? 4 : 1));
  f.descriptors = cv::Mat(static_cast<int>(n), columns, element);
  if (!message.descriptors.empty()) {
    std::memcpy(f.descriptors.data, message.descriptors.data(), message.descriptors.size());
  }
  keyframe.map_point_ids.assign(message.map_point_ids.begin(), message.map_point_ids.end());
  return keyframe;
}

geometry::StereoCamera CameraOfKeyframe(const stereo_fabmap_slam::Keyframe& message) {
  geometry::StereoCamera camera;
  camera.size = cv::Size(static_cast<int>(message.width), static_cast<int>(message.height));
  camera.fx = message.fx;
  camera.fy = message.fy;
  camera.cx = message.cx;
  camera.cy = message.cy;
  camera.baseline = message.baseline;
  return camera;
}

stereo_fabmap_slam::KeyframeUpdate ToKeyframeUpdateMessage(const map::KeyframeUpdate& update) {
  stereo_fabmap_slam::KeyframeUpdate message;
  for (const auto& [id, pose] : update.keyframe_poses) {
    message.keyframe_ids.push_back(static_cast<std::uint64_t>(id));
    message.keyframe_poses.push_back(ToPoseMessage(pose));
  }
  for (const auto& [id, position] : update.point_positions) {
    message.point_ids.push_back(id);
    geometry_msgs::Point point;
    point.x = position.x();
    point.y = position.y();
    point.z = position.z();
    message.point_positions.push_back(point);
  }
  message.removed_point_ids.assign(update.removed_points.begin(), update.removed_points.end());
  return message;
}

map::KeyframeUpdate FromKeyframeUpdateMessage(const stereo_fabmap_slam::KeyframeUpdate& message) {
  if (message.keyframe_ids.size() != message.keyframe_poses.size() ||
      message.point_ids.size() != message.point_positions.size()) {
    throw std::invalid_argument("KeyframeUpdate message: arrays of different lengths");
  }
  map::KeyframeUpdate update;
  for (std::size_t i = 0; i < message.keyframe_ids.size(); ++i) {
    update.keyframe_poses.emplace_back(static_cast<std::int64_t>(message.keyframe_ids[i]),
                                       FromPoseMessage(message.keyframe_poses[i]));
  }
  for (std::size_t i = 0; i < message.point_ids.size(); ++i) {
    const geometry_msgs::Point& p = message.point_positions[i];
    update.point_positions.emplace_back(message.point_ids[i], Eigen::Vector3d(p.x, p.y, p.z));
  }
  update.removed_points.assign(message.removed_point_ids.begin(), message.removed_point_ids.end());
  return update;
}

}  // namespace stereo_fabmap_slam::ros_conversions
