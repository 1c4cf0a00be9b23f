#include "stereo_fabmap_slam/odometry/keyframe_policy.h"

#include <stdexcept>

namespace stereo_fabmap_slam::odometry {

void KeyframePolicyOptions::Visit(io::OptionVisitor& visitor) {
  visitor.Visit("min_tracked_ratio", &min_tracked_ratio);
  visitor.Visit("min_tracked_points", &min_tracked_points);
  visitor.Visit("max_translation", &max_translation);
  visitor.Visit("max_rotation_deg", &max_rotation_deg);
  visitor.Visit("max_interval", &max_interval);
  visitor.Visit("min_interval", &min_interval);
}

void KeyframePolicyOptions::Validate() const {
  if (!(min_tracked_ratio >= 0 && min_tracked_ratio <= 1)) {
    throw std::invalid_argument("keyframes.min_tracked_ratio must lie in [0, 1]");
  }
  if (min_tracked_points < 0)
    throw std::invalid_argument("keyframes.min_tracked_points must be >= 0");
  if (!(max_translation > 0) || !(max_rotation_deg > 0) || !(max_interval > 0)) {
    throw std::invalid_argument(
        "keyframes: max_translation, max_rotation_deg, max_interval must be > 0");
  }
  if (!(min_interval >= 0 && min_interval < max_interval)) {
    throw std::invalid_argument("keyframes.min_interval must lie in [0, max_interval)");
  }
}

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
