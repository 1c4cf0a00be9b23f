#pragma once

// REP-105 frames for the tracker's poses. The core library tracks the rectified left camera in
// a world frame that is the camera's pose at the first frame (z forward, as the optics). ROS's
// odom frame is the robot base's pose at that frame instead, so that the odometry plugs into a
// robot's tf tree (map -> odom -> base_link -> camera). The camera's mounting on the base,
// T_base_camera, converts between the two; every pose and point that leaves the tracker is in
// odom, every one that comes back is converted to the library's world.

#include <Eigen/Geometry>

#include "stereo_fabmap_slam/geometry/pose_covariance.h"
#include "stereo_fabmap_slam/map/keyframe.h"
#include "stereo_fabmap_slam/map/keyframe_update.h"

namespace stereo_fabmap_slam::ros_conversions {

class BaseFrameConvention {
 public:
  // T_base_camera: the rectified left camera in the base frame.
  explicit BaseFrameConvention(const Eigen::Isometry3d& T_base_camera)
      : T_base_camera_(T_base_camera) {}

  const Eigen::Isometry3d& T_base_camera() const { return T_base_camera_; }

  // A pose (T_world_x) or point given in the library's world, expressed in odom, and back. A
  // camera pose stays a camera pose; only the reference frame changes.
  Eigen::Isometry3d ToOdom(const Eigen::Isometry3d& T_world_x) const {
    return T_base_camera_ * T_world_x;
  }
  Eigen::Vector3d ToOdom(const Eigen::Vector3d& world) const { return T_base_camera_ * world; }
  Eigen::Isometry3d FromOdom(const Eigen::Isometry3d& T_odom_x) const {
    return T_base_camera_.inverse() * T_odom_x;
  }
  Eigen::Vector3d FromOdom(const Eigen::Vector3d& odom) const {
    return T_base_camera_.inverse() * odom;
  }

  // The base's pose in odom for a camera pose in the library's world: T_odom_base.
  Eigen::Isometry3d BaseInOdom(const Eigen::Isometry3d& T_world_camera) const {
    return T_base_camera_ * T_world_camera * T_base_camera_.inverse();
  }

  // The base pose's covariance in the base's own axes (right perturbation), from the camera
  // pose's (right perturbation, camera axes): what a twist's covariance is built from.
  geometry::PoseCovariance BaseCovariance(const geometry::PoseCovariance& camera_covariance) const;
  // The covariance of BaseInOdom(T_world_camera), with axes in odom as nav_msgs/Odometry's pose
  // covariance is given, from the camera pose's (right perturbation, camera axes).
  geometry::PoseCovariance BaseCovarianceInOdom(
      const Eigen::Isometry3d& T_world_camera,
      const geometry::PoseCovariance& camera_covariance) const;

  // A keyframe with its pose in odom (its features are relative to the camera and stay).
  map::Keyframe KeyframeToOdom(map::Keyframe keyframe) const;
  // A bundle adjustment update given in odom (as the Backend works there), in the library's
  // world.
  map::KeyframeUpdate UpdateFromOdom(map::KeyframeUpdate update) const;

 private:
  Eigen::Isometry3d T_base_camera_;
};

}  // namespace stereo_fabmap_slam::ros_conversions
