#pragma once

#include <Eigen/Geometry>

#include "stereo_fabmap_slam/io/trajectory.h"

namespace stereo_fabmap_slam::evaluation {

// The trajectory types are io's (the SLAM writes its trajectories without evaluation); the
// evaluation speaks of them under these names.
using StampedPose = io::StampedPose;
using Trajectory = io::Trajectory;
using io::PoseFromTranslationQuaternion;

// Moves a body-frame trajectory (T_world_body, e.g. EuRoC ground truth) to a sensor mounted at
// T_body_sensor (EuRoC's T_BS): T_world_sensor = T_world_body * T_body_sensor.
Trajectory TransformToSensorFrame(const Trajectory& body_trajectory,
                                  const Eigen::Isometry3d& T_body_sensor);

}  // namespace stereo_fabmap_slam::evaluation
