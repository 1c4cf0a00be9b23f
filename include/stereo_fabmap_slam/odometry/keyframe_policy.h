#pragma once

#include <string>

#include "stereo_fabmap_slam/io/option_reader.h"

namespace stereo_fabmap_slam::odometry {

struct KeyframePolicyOptions {
  double min_tracked_ratio = 0.7;  // tracked points / most tracked in a frame since the keyframe
  int min_tracked_points = 80;     // fewer tracked map points: new keyframe
  double max_translation = 0.25;   // [m] since the last keyframe
  double max_rotation_deg = 10.0;  // [deg] since the last keyframe
  double max_interval = 1.0;       // [s] since the last keyframe
  double min_interval = 0.0;       // [s] never closer (except when tracking is weak)

  void Visit(io::OptionVisitor& visitor);
  void Validate() const;
};

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
