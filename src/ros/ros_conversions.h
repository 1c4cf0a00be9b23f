#pragma once

// Every conversion between ROS messages and the core library's types, in one tested place.

#include <cstdint>
#include <string>

#include <geometry_msgs/Pose.h>
#include <geometry_msgs/Transform.h>
#include <ros/time.h>
#include <sensor_msgs/CameraInfo.h>
#include <sensor_msgs/Image.h>
#include <Eigen/Geometry>
#include <opencv2/core.hpp>

#include <stereo_fabmap_slam/Keyframe.h>
#include <stereo_fabmap_slam/KeyframeUpdate.h>
#include <stereo_fabmap_slam/LoopEdge.h>

#include "stereo_fabmap_slam/camera/stereo_rectifier.h"
#include "stereo_fabmap_slam/map/keyframe.h"
#include "stereo_fabmap_slam/map/keyframe_update.h"
#include "stereo_fabmap_slam/map/loop_edge.h"

namespace stereo_fabmap_slam::ros_conversions {

ros::Time ToRosTime(std::int64_t timestamp_ns);
std::int64_t ToNanoseconds(const ros::Time& time);
// Seconds as the offline tools compute them from nanoseconds (1e-9 * ns): the same double for
// the same stamp, which ros::Time::toSec (sec + 1e-9 * nsec) is not to the last bit.
double ToSeconds(const ros::Time& time);

// A mono8 image message holding a copy of `image` (which must be CV_8UC1).
sensor_msgs::ImagePtr ToMono8ImageMessage(const cv::Mat& image, const ros::Time& stamp,
                                          const std::string& frame_id);

// Why an image message cannot be what it says (its data shorter than step x height, a step
// shorter than a row, no pixels), or "" if it is consistent. Encodings whose pixel size is
// unknown are checked for size only; whether cv_bridge can convert them is another question.
std::string MalformedImageReason(const sensor_msgs::Image& image);

geometry_msgs::Pose ToPoseMessage(const Eigen::Isometry3d& pose);
Eigen::Isometry3d FromPoseMessage(const geometry_msgs::Pose& pose);
geometry_msgs::Transform ToTransformMessage(const Eigen::Isometry3d& transform);
Eigen::Isometry3d FromTransformMessage(const geometry_msgs::Transform& transform);

// CameraInfo <-> rectification parameters (K, D, R, P). Only the plumb_bob model (4 or 5
// coefficients) is accepted; anything else throws std::invalid_argument.
camera::RectificationParameters FromCameraInfo(const sensor_msgs::CameraInfo& info);
sensor_msgs::CameraInfo ToCameraInfo(const camera::RectificationParameters& parameters,
                                     const std::string& frame_id);

// The rectifier of a stereo pair described by two CameraInfo messages; T_body_left_raw places
// the raw left camera in the body frame (CameraInfo does not carry it).
camera::StereoRectifier RectifierFromCameraInfo(const sensor_msgs::CameraInfo& left,
                                                const sensor_msgs::CameraInfo& right,
                                                const Eigen::Isometry3d& T_body_left_raw);

// Keyframes and backend updates. The camera travels with each keyframe so that consumers need
// no calibration of their own.
stereo_fabmap_slam::Keyframe ToKeyframeMessage(const map::Keyframe& keyframe,
                                               const geometry::StereoCamera& camera,
                                               const std::string& frame_id);
map::Keyframe FromKeyframeMessage(const stereo_fabmap_slam::Keyframe& message);
geometry::StereoCamera CameraOfKeyframe(const stereo_fabmap_slam::Keyframe& message);
stereo_fabmap_slam::KeyframeUpdate ToKeyframeUpdateMessage(const map::KeyframeUpdate& update);
map::KeyframeUpdate FromKeyframeUpdateMessage(const stereo_fabmap_slam::KeyframeUpdate& message);

// Loop and relocalization edges.
stereo_fabmap_slam::LoopEdge ToLoopEdgeMessage(const map::LoopEdge& edge);
map::LoopEdge FromLoopEdgeMessage(const stereo_fabmap_slam::LoopEdge& message);

}  // namespace stereo_fabmap_slam::ros_conversions
