#include "ros_conversions.h"

#include <algorithm>
#include <cstring>
#include <stdexcept>

#include <cv_bridge/cv_bridge.h>
#include <sensor_msgs/image_encodings.h>
#include <tf2_eigen/tf2_eigen.h>

namespace stereo_fabmap_slam::ros_conversions {

namespace {

// Descriptors (one per row, CV_8U binary or CV_32F) as the bytes of a message, row-major.
void PackDescriptors(const cv::Mat& descriptors, std::vector<std::uint8_t>* bytes,
                     std::uint32_t* row_bytes, std::uint8_t* are_float) {
  const cv::Mat continuous = descriptors.isContinuous() ? descriptors : descriptors.clone();
  *are_float = continuous.type() == CV_32F;
  *row_bytes = static_cast<std::uint32_t>(continuous.cols * continuous.elemSize());
  bytes->assign(continuous.data, continuous.data + continuous.total() * continuous.elemSize());
}

cv::Mat UnpackDescriptors(const std::vector<std::uint8_t>& bytes, std::uint32_t row_bytes,
                          bool are_float) {
  if (row_bytes == 0) return cv::Mat();
  const int rows = static_cast<int>(bytes.size() / row_bytes);
  cv::Mat descriptors(rows, static_cast<int>(row_bytes / (are_float ? 4 : 1)),
                      are_float ? CV_32F : CV_8U);
  if (!bytes.empty()) std::memcpy(descriptors.data, bytes.data(), bytes.size());
  return descriptors;
}

}  // namespace

ros::Time ToRosTime(std::int64_t timestamp_ns) {
  ros::Time time;
  time.fromNSec(static_cast<std::uint64_t>(timestamp_ns));
  return time;
}

double ToSeconds(const ros::Time& time) { return static_cast<double>(ToNanoseconds(time)) * 1e-9; }

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

std::string MalformedImageReason(const sensor_msgs::Image& image) {
  if (image.width == 0 || image.height == 0) return "no pixels (0 wide or high)";
  const std::size_t needed = static_cast<std::size_t>(image.step) * image.height;
  if (image.data.size() < needed) {
    return std::to_string(image.data.size()) + " bytes of data for " +
           std::to_string(image.height) + " rows of " + std::to_string(image.step) + " bytes";
  }
  try {
    const std::size_t row = static_cast<std::size_t>(image.width) *
                            sensor_msgs::image_encodings::numChannels(image.encoding) *
                            sensor_msgs::image_encodings::bitDepth(image.encoding) / 8;
    if (image.step < row) {
      return "a step of " + std::to_string(image.step) + " bytes for rows of " +
             std::to_string(row) + " bytes (" + image.encoding + ")";
    }
  } catch (const std::runtime_error&) {
    // An encoding sensor_msgs does not know: its row size cannot be checked here.
  }
  return "";
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
  message.starts_new_segment = keyframe.starts_new_segment;
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
  message.size.resize(n);
  message.angle.resize(n);
  message.response.resize(n);
  message.octave.resize(n);
  message.class_id.resize(n);
  for (std::size_t i = 0; i < n; ++i) {
    const cv::KeyPoint& keypoint = f.keypoints[i];
    message.u[i] = keypoint.pt.x;
    message.v[i] = keypoint.pt.y;
    message.size[i] = keypoint.size;
    message.angle[i] = keypoint.angle;
    message.response[i] = keypoint.response;
    message.octave[i] = keypoint.octave;
    message.class_id[i] = keypoint.class_id;
    message.points[i].x = f.points[i].x();
    message.points[i].y = f.points[i].y();
    message.points[i].z = f.points[i].z();
  }
  PackDescriptors(f.descriptors, &message.descriptors, &message.descriptor_bytes,
                  &message.descriptors_are_float);
  PackDescriptors(keyframe.place_descriptors, &message.place_descriptors,
                  &message.place_descriptor_bytes, &message.place_descriptors_are_float);
  message.map_point_ids.assign(keyframe.map_point_ids.begin(), keyframe.map_point_ids.end());
  return message;
}

map::Keyframe FromKeyframeMessage(const stereo_fabmap_slam::Keyframe& message) {
  const std::size_t n = message.u.size();
  if (message.v.size() != n || message.u_right.size() != n || message.points.size() != n ||
      message.map_point_ids.size() != n || message.size.size() != n || message.angle.size() != n ||
      message.response.size() != n || message.octave.size() != n || message.class_id.size() != n ||
      message.descriptors.size() != n * message.descriptor_bytes ||
      (message.place_descriptor_bytes == 0
           ? !message.place_descriptors.empty()
           : message.place_descriptors.size() % message.place_descriptor_bytes != 0) ||
      (message.place_descriptors_are_float && message.place_descriptor_bytes % 4 != 0) ||
      (message.descriptors_are_float && message.descriptor_bytes % 4 != 0)) {
    throw std::invalid_argument("Keyframe message: arrays of different lengths");
  }
  map::Keyframe keyframe;
  keyframe.id = static_cast<std::int64_t>(message.id);
  keyframe.timestamp = ToSeconds(message.header.stamp);
  keyframe.T_world_camera = FromPoseMessage(message.pose);
  keyframe.starts_new_segment = message.starts_new_segment;
  features::StereoFeatures& f = keyframe.features;
  f.keypoints.resize(n);
  f.points.resize(n);
  f.u_right.assign(message.u_right.begin(), message.u_right.end());
  for (std::size_t i = 0; i < n; ++i) {
    f.keypoints[i] =
        cv::KeyPoint(cv::Point2f(message.u[i], message.v[i]), message.size[i], message.angle[i],
                     message.response[i], message.octave[i], message.class_id[i]);
    f.points[i] = Eigen::Vector3d(message.points[i].x, message.points[i].y, message.points[i].z);
  }
  f.descriptors = UnpackDescriptors(message.descriptors, message.descriptor_bytes,
                                    message.descriptors_are_float);
  keyframe.place_descriptors =
      UnpackDescriptors(message.place_descriptors, message.place_descriptor_bytes,
                        message.place_descriptors_are_float);
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

stereo_fabmap_slam::LoopEdge ToLoopEdgeMessage(const map::LoopEdge& edge) {
  stereo_fabmap_slam::LoopEdge message;
  message.query_id = static_cast<std::uint64_t>(edge.query_id);
  message.match_id = static_cast<std::uint64_t>(edge.match_id);
  message.T_match_query = ToPoseMessage(edge.T_match_query);
  for (int r = 0; r < 6; ++r) {
    for (int c = 0; c < 6; ++c) message.information[r * 6 + c] = edge.information(r, c);
  }
  message.inliers = edge.inliers;
  for (const auto& [query_point, match_point] : edge.shared_points) {
    message.shared_query_points.push_back(query_point);
    message.shared_match_points.push_back(match_point);
  }
  message.probability = edge.probability;
  return message;
}

map::LoopEdge FromLoopEdgeMessage(const stereo_fabmap_slam::LoopEdge& message) {
  map::LoopEdge edge;
  edge.query_id = static_cast<std::int64_t>(message.query_id);
  edge.match_id = static_cast<std::int64_t>(message.match_id);
  edge.T_match_query = FromPoseMessage(message.T_match_query);
  for (int r = 0; r < 6; ++r) {
    for (int c = 0; c < 6; ++c) edge.information(r, c) = message.information[r * 6 + c];
  }
  edge.inliers = message.inliers;
  // Pairs: a message whose two lists differ in length gives the pairs both have.
  const std::size_t pairs =
      std::min(message.shared_query_points.size(), message.shared_match_points.size());
  for (std::size_t i = 0; i < pairs; ++i) {
    edge.shared_points.emplace_back(message.shared_query_points[i], message.shared_match_points[i]);
  }
  edge.probability = message.probability;
  return edge;
}

geometry_msgs::Transform ToTransformMessage(const Eigen::Isometry3d& transform) {
  const geometry_msgs::Pose pose = ToPoseMessage(transform);
  geometry_msgs::Transform message;
  message.translation.x = pose.position.x;
  message.translation.y = pose.position.y;
  message.translation.z = pose.position.z;
  message.rotation = pose.orientation;
  return message;
}

Eigen::Isometry3d FromTransformMessage(const geometry_msgs::Transform& transform) {
  geometry_msgs::Pose pose;
  pose.position.x = transform.translation.x;
  pose.position.y = transform.translation.y;
  pose.position.z = transform.translation.z;
  pose.orientation = transform.rotation;
  return FromPoseMessage(pose);
}

}  // namespace stereo_fabmap_slam::ros_conversions
