#pragma once

#include <vector>

#include <Eigen/Geometry>

namespace stereo_fabmap_slam::evaluation {

// Pose of a sensor in a world frame at a time: T_world_sensor.
struct StampedPose {
  double timestamp = 0;  // [s]; for KITTI files, the line index
  Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
};

using Trajectory = std::vector<StampedPose>;

// Moves a body-frame trajectory (T_world_body, e.g. EuRoC ground truth) to a sensor mounted at
// T_body_sensor (EuRoC's T_BS): T_world_sensor = T_world_body * T_body_sensor.
Trajectory TransformToSensorFrame(const Trajectory& body_trajectory,
                                  const Eigen::Isometry3d& T_body_sensor);

// Pose from a translation and a quaternion (any norm; normalised here).
Eigen::Isometry3d PoseFromTranslationQuaternion(const Eigen::Vector3d& translation,
                                                const Eigen::Quaterniond& rotation);

}  // namespace stereo_fabmap_slam::evaluation
