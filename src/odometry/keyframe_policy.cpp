#include "stereo_fabmap_slam/odometry/keyframe_policy.h"

#include <stdexcept>

namespace stereo_fabmap_slam::odometry {

KeyframePolicy::KeyframePolicy(const KeyframePolicyOptions& options) : options_(options) {
  options_.Validate();
}

KeyframeDecision KeyframePolicy::Decide(const KeyframePolicyInput& in) const {
  if (in.tracking_weak) return {true, "tracking weak"};
  if (in.time_since_last < options_.min_interval) return {};
  if (in.tracked_points < options_.min_tracked_points) return {true, "few tracked points"};
  if (in.tracked_points < options_.min_tracked_ratio * in.reference_tracked_points) {
    return {true, "tracked ratio low"};
  }
  if (in.translation_since_last > options_.max_translation) return {true, "translation"};
  if (in.rotation_since_last_deg > options_.max_rotation_deg) return {true, "rotation"};
  if (in.time_since_last > options_.max_interval) return {true, "interval"};
  return {};
}

}  // namespace stereo_fabmap_slam::odometry
