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
// the two stamps differ by at most max_dt seconds. Either may be in any order and repeat stamps
// (of equal reference stamps the first in the file is taken). The pairs come out in the order of
// the estimate.
std::vector<AssociatedPair> AssociateByTimestamp(const Trajectory& reference,
                                                 const Trajectory& estimate, double max_dt);

}  // namespace stereo_fabmap_slam::evaluation
