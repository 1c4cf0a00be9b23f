#include "stereo_fabmap_slam/evaluation/association.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace stereo_fabmap_slam::evaluation {

std::vector<AssociatedPair> AssociateByTimestamp(const Trajectory& reference,
                                                 const Trajectory& estimate, double max_dt) {
  if (!(max_dt >= 0)) throw std::invalid_argument("max_dt must not be negative");
  std::vector<AssociatedPair> pairs;
  if (reference.empty()) return pairs;
  const auto earlier = [](const StampedPose& pose, double t) { return pose.timestamp < t; };
  for (std::size_t e = 0; e < estimate.size(); ++e) {
    const double t = estimate[e].timestamp;
    const auto after = std::lower_bound(reference.begin(), reference.end(), t, earlier);
    std::size_t best = static_cast<std::size_t>(after - reference.begin());
    if (best == reference.size() ||
        (best > 0 && t - reference[best - 1].timestamp < reference[best].timestamp - t)) {
      --best;
    }
    if (std::abs(reference[best].timestamp - t) <= max_dt) pairs.push_back({best, e});
  }
  return pairs;
}

}  // namespace stereo_fabmap_slam::evaluation
