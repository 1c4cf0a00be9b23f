#pragma once

#include <optional>

#include <Eigen/Geometry>

#include "stereo_fabmap_slam/evaluation/trajectory.h"

namespace stereo_fabmap_slam::evaluation {

// The pose at `time` between the two poses of a time-sorted trajectory around it (linear in
// translation, slerp in rotation), or nothing if `time` lies outside the trajectory or the two
// are more than max_gap seconds apart. Ground truth at 200 Hz would be up to 2.5 ms off when
// taken at the nearest stamp: a pixel at EuRoC's turning rates, too much for a 2.5 px test.
std::optional<Eigen::Isometry3d> InterpolatePose(const Trajectory& trajectory, double time,
                                                 double max_gap);

}  // namespace stereo_fabmap_slam::evaluation
