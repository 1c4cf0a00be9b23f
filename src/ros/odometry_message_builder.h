#pragma once

#include <optional>
#include <string>

#include <nav_msgs/Odometry.h>
#include <ros/time.h>

#include "base_frame_convention.h"

namespace stereo_fabmap_slam::ros_conversions {

// The tracker's nav_msgs/Odometry: the base's pose in odom with its covariance (odom axes), and
// the twist in the base frame from the previous frame's pose, as REP-105 and robot_localization
// expect.
//
// Covariance: the Gauss-Newton covariance of the tracked camera pose from its inlier points
// and the pixel noise (geometry::StereoPoseCovariance), carried to the base. It is this frame's
// uncertainty relative to the local map, not the drift accumulated since the start; a fusion
// node should take the odometry differentially (robot_localization's `differential`). The twist
// covariance is that of the difference of two such poses, (C_previous + C_current) / dt^2.
// What is not known (the first frame, a new segment of odometry) carries 1e6 on the diagonal.
class OdometryMessageBuilder {
 public:
  OdometryMessageBuilder(const BaseFrameConvention& frames, std::string odom_frame,
                         std::string base_frame)
      : frames_(frames), odom_frame_(std::move(odom_frame)), base_frame_(std::move(base_frame)) {}

  // `continues_previous`: this frame's pose follows the last one built without a jump (false
  // after a tracking loss or reset).
  nav_msgs::Odometry Build(const ros::Time& stamp, const Eigen::Isometry3d& T_world_camera,
                           const geometry::PoseCovariance& camera_covariance,
                           bool continues_previous);

 private:
  struct Previous {
    ros::Time stamp;
    Eigen::Isometry3d T_odom_base;
    geometry::PoseCovariance covariance_in_base;
  };
  BaseFrameConvention frames_;
  std::string odom_frame_, base_frame_;
  std::optional<Previous> previous_;
};

}  // namespace stereo_fabmap_slam::ros_conversions
