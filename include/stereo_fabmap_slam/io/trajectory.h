#pragma once

#include <vector>

#include <Eigen/Geometry>

namespace stereo_fabmap_slam::io {

// Pose of a sensor in a world frame at a time: T_world_sensor.
struct StampedPose {
  double timestamp = 0;  // [s]; for KITTI files, the line index
  Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
};
using Trajectory = std::vector<StampedPose>;

// Pose from a translation and a quaternion (any norm; normalised here).
Eigen::Isometry3d PoseFromTranslationQuaternion(const Eigen::Vector3d& translation,
                                                const Eigen::Quaterniond& rotation);

}  // namespace stereo_fabmap_slam::io
