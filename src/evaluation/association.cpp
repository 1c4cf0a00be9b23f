#include "stereo_fabmap_slam/evaluation/association.h"

#include <algorithm>
#include <cmath>
#include <numeric>
#include <stdexcept>

namespace stereo_fabmap_slam::evaluation {

std::vector<AssociatedPair> AssociateByTimestamp(const Trajectory& reference,
                                                 const Trajectory& estimate, double max_dt) {
  if (!(max_dt >= 0)) throw std::invalid_argument("max_dt must not be negative");
  std::vector<AssociatedPair> pairs;
  if (reference.empty()) return pairs;
  // The reference in time order (stable: of equal stamps, the first in the file wins, as with
  // evo's argmin); files of other systems may repeat or reorder stamps.
  std::vector<std::size_t> order(reference.size());
  std::iota(order.begin(), order.end(), 0);
  std::stable_sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) {
    return reference[a].timestamp < reference[b].timestamp;
  });
  const auto earlier = [&](std::size_t index, double t) { return reference[index].timestamp < t; };
  for (std::size_t e = 0; e < estimate.size(); ++e) {
    const double t = estimate[e].timestamp;
    const auto after = std::lower_bound(order.begin(), order.end(), t, earlier);
    std::size_t k = static_cast<std::size_t>(after - order.begin());
    // The nearer of the neighbours; on a tie the earlier, and of equal stamps the first.
    if (k == order.size() ||
        (k > 0 && t - reference[order[k - 1]].timestamp <= reference[order[k]].timestamp - t)) {
      --k;
      while (k > 0 && reference[order[k - 1]].timestamp == reference[order[k]].timestamp) --k;
    }
    const std::size_t best = order[k];
    if (std::abs(reference[best].timestamp - t) <= max_dt) pairs.push_back({best, e});
  }
  return pairs;
}

}  // namespace stereo_fabmap_slam::evaluation
