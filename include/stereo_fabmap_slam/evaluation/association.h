#pragma once

#include <cstddef>
#include <vector>

#include "stereo_fabmap_slam/evaluation/trajectory.h"

namespace stereo_fabmap_slam::evaluation {

struct AssociatedPair {
  std::size_t reference = 0;  // index into the reference trajectory
  std::size_t estimate = 0;   // index into the estimated trajectory
};

// Pairs every estimated pose with the reference pose nearest in time, and keeps the pair only if
// the two stamps differ by at most max_dt seconds. Both trajectories must be sorted by time.
// The pairs come out in the order of the estimate.
std::vector<AssociatedPair> AssociateByTimestamp(const Trajectory& reference,
                                                 const Trajectory& estimate, double max_dt);

}  // namespace stereo_fabmap_slam::evaluation
