#include "stereo_fabmap_slam/odometry/keyframe_policy.h"

#include <stdexcept>

namespace stereo_fabmap_slam::odometry {

KeyframePolicy::KeyframePolicy(const KeyframePolicyOptions& options) : options_(options) {
  options_.Validate();
}

std::string KeyframePolicy::ExceededBound(const KeyframeMeasures& measures,
                                          int reference_settled_points) const {
  if (measures.settled_points < options_.min_tracked_ratio * reference_settled_points) {
    return "tracked ratio low";
  }
  if (measures.translation > options_.max_translation) return "translation";
  if (measures.rotation_deg > options_.max_rotation_deg) return "rotation";
  if (measures.time > options_.max_interval) return "interval";
  return "";
}

KeyframeDecision KeyframePolicy::Decide(const KeyframePolicyInput& in) const {
  if (in.tracking_weak) return {true, "tracking weak"};
  if (in.now.time < options_.min_interval) return {};
  if (in.tracked_points < options_.min_tracked_points) return {true, "few tracked points"};
  if (std::string bound = ExceededBound(in.now, in.reference_settled_points); !bound.empty()) {
    return {true, bound};
  }
  if (in.before_next_frame) {
    const std::string bound = ExceededBound(*in.before_next_frame, in.reference_settled_points);
    if (!bound.empty()) return {true, bound + " before the next tracked frame"};
  }
  return {};
}

}  // namespace stereo_fabmap_slam::odometry
