#pragma once

#include <string>

#include "stereo_fabmap_slam/io/option_reader.h"
#include "stereo_fabmap_slam/odometry/odometry_options.h"

namespace stereo_fabmap_slam::odometry {

struct KeyframePolicyInput {
  int tracked_points = 0;              // map points matched and inlier in this frame
  int reference_tracked_points = 0;    // most map points tracked in a frame since the last keyframe
  double translation_since_last = 0;   // [m]
  double rotation_since_last_deg = 0;  // [deg]
  double time_since_last = 0;          // [s]
  bool tracking_weak = false;
};

struct KeyframeDecision {
  bool insert = false;
  std::string reason;  // why (empty if not inserted)
};

// Decides whether the current frame becomes a keyframe.
class KeyframePolicy {
 public:
  explicit KeyframePolicy(const KeyframePolicyOptions& options);
  KeyframeDecision Decide(const KeyframePolicyInput& input) const;

 private:
  KeyframePolicyOptions options_;
};

}  // namespace stereo_fabmap_slam::odometry
