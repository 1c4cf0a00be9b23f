#pragma once

// Every conversion between ROS messages and the core library's types, in one tested place.

#include <cstdint>
#include <string>

#include <geometry_msgs/Pose.h>
#include <ros/time.h>
#include <sensor_msgs/CameraInfo.h>
#include <sensor_msgs/Image.h>
#include <Eigen/Geometry>
#include <opencv2/core.hpp>

#include <ros/node_handle.h>
#include <stereo_fabmap_slam/Keyframe.h>
#include <stereo_fabmap_slam/KeyframeUpdate.h>

#include "stereo_fabmap_slam/camera/stereo_rectifier.h"
#include "stereo_fabmap_slam/io/option_reader.h"
#include "stereo_fabmap_slam/odometry/keyframe_data.h"

namespace stereo_fabmap_slam::ros_conversions {

ros::Time ToRosTime(std::int64_t timestamp_ns);
std::int64_t ToNanoseconds(const ros::Time& time);

// A mono8 image message holding a copy of `image` (which must be CV_8UC1).
sensor_msgs::ImagePtr ToMono8ImageMessage(const cv::Mat& image, const ros::Time& stamp,
                                          const std::string& frame_id);

geometry_msgs::Pose ToPoseMessage(const Eigen::Isometry3d& pose);
Eigen::Isometry3d FromPoseMessage(const geometry_msgs::Pose& pose);

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
stereo_fabmap_slam::Keyframe ToKeyframeMessage(const odometry::KeyframeData& keyframe,
                                               const camera::StereoCamera& camera,
                                               const std::string& frame_id);
odometry::KeyframeData FromKeyframeMessage(const stereo_fabmap_slam::Keyframe& message);
camera::StereoCamera CameraOfKeyframe(const stereo_fabmap_slam::Keyframe& message);
stereo_fabmap_slam::KeyframeUpdate ToKeyframeUpdateMessage(const odometry::KeyframeUpdate& update);
odometry::KeyframeUpdate FromKeyframeUpdateMessage(
    const stereo_fabmap_slam::KeyframeUpdate& message);

// Fills Options fields from ROS parameters "<namespace>/<section>/<key>" (e.g. the private
// "~features/max_features" after `rosparam load config/euroc.yaml`); absent parameters keep the
// default, a parameter of the wrong type throws std::invalid_argument naming it.
class RosParameterReader : public io::OptionVisitor {
 public:
  RosParameterReader(const ros::NodeHandle& node, const std::string& section);
  void Visit(const std::string& key, double* value) override;
  void Visit(const std::string& key, int* value) override;
  void Visit(const std::string& key, bool* value) override;
  void Visit(const std::string& key, std::string* value) override;

 private:
  template <typename T>
  void Get(const std::string& key, T* value, const char* expected);

  ros::NodeHandle node_;
  std::string section_;
};

}  // namespace stereo_fabmap_slam::ros_conversions
