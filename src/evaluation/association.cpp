#include "stereo_fabmap_slam/evaluation/association.h"

#include <algorithm>
#include <cmath>
#include <numeric>
#include <stdexcept>

namespace stereo_fabmap_slam::evaluation {
namespace {

// Finds, for any time, the pose of a trajectory nearest to it, as numpy's argmin over the
// absolute differences in evo: of equal differences the pose first in the file wins. Files of
// other systems may repeat or reorder stamps, so the search runs over a stably sorted index.
class NearestInTime {
 public:
  explicit NearestInTime(const Trajectory& trajectory)
      : trajectory_(trajectory), order_(trajectory.size()) {
    std::iota(order_.begin(), order_.end(), 0);
    std::stable_sort(order_.begin(), order_.end(), [&](std::size_t a, std::size_t b) {
      return trajectory_[a].timestamp < trajectory_[b].timestamp;
    });
  }

  // The index of the pose nearest to t; the trajectory must not be empty.
  std::size_t Find(double t) const {
    const auto earlier = [&](std::size_t index, double time) {
      return trajectory_[index].timestamp < time;
    };
    const std::size_t k = static_cast<std::size_t>(
        std::lower_bound(order_.begin(), order_.end(), t, earlier) - order_.begin());
    // Candidates: the first of the stamps at or after t and the first of those before it (a
    // stable sort puts the first in the file first among equal stamps).
    std::size_t best = order_.size();
    double best_difference = 0;
    const auto consider = [&](std::size_t index) {
      const double difference = std::abs(trajectory_[index].timestamp - t);
      if (best == order_.size() || difference < best_difference ||
          (difference == best_difference && index < best)) {
        best = index;
        best_difference = difference;
      }
    };
    if (k < order_.size()) consider(order_[k]);
    if (k > 0) consider(order_[FirstOfEqualStamps(k - 1)]);
    return best;
  }

 private:
  std::size_t FirstOfEqualStamps(std::size_t k) const {
    while (k > 0 && trajectory_[order_[k - 1]].timestamp == trajectory_[order_[k]].timestamp) --k;
    return k;
  }

  const Trajectory& trajectory_;
  std::vector<std::size_t> order_;
};

}  // namespace

std::vector<AssociatedPair> AssociateByTimestamp(const Trajectory& reference,
                                                 const Trajectory& estimate, double max_dt) {
  if (!(max_dt >= 0)) throw std::invalid_argument("max_dt must not be negative");
  std::vector<AssociatedPair> pairs;
  if (reference.empty() || estimate.empty()) return pairs;
  // evo's associate_trajectories (evo_ape with the reference first): the shorter trajectory is
  // associated into the longer one, the estimate into the reference when they are as long.
  // Which side searches matters once a stamp repeats: a pose of the searching side is used at
  // most once, one of the searched side may be used by several.
  const bool estimate_longer = estimate.size() > reference.size();
  const Trajectory& searching = estimate_longer ? reference : estimate;
  const Trajectory& searched = estimate_longer ? estimate : reference;
  const NearestInTime nearest_in_searched(searched);
  for (std::size_t i = 0; i < searching.size(); ++i) {
    const std::size_t nearest = nearest_in_searched.Find(searching[i].timestamp);
    if (!(std::abs(searched[nearest].timestamp - searching[i].timestamp) <= max_dt)) continue;
    pairs.push_back(estimate_longer ? AssociatedPair{i, nearest} : AssociatedPair{nearest, i});
  }
  return pairs;
}

}  // namespace stereo_fabmap_slam::evaluation
