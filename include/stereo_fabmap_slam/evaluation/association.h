#pragma once

#include <cstddef>
#include <vector>

#include "stereo_fabmap_slam/evaluation/trajectory.h"

namespace stereo_fabmap_slam::evaluation {

struct AssociatedPair {
  std::size_t reference = 0;  // index into the reference trajectory
  std::size_t estimate = 0;   // index into the estimated trajectory
};

// Pairs poses by time as evo does (evo_ape's associate_trajectories): each pose of the shorter
// trajectory (the estimate when both are as long) takes the pose of the other nearest in time,
// the first in that file on equal differences, and the pair is kept only if the two stamps
// differ by at most max_dt seconds. Either may be in any order and repeat stamps. The pairs come
// out in the file order of the shorter trajectory.
std::vector<AssociatedPair> AssociateByTimestamp(const Trajectory& reference,
                                                 const Trajectory& estimate, double max_dt);

}  // namespace stereo_fabmap_slam::evaluation
