#pragma once

#include <optional>
#include <string>

#include "stereo_fabmap_slam/io/option_reader.h"
#include "stereo_fabmap_slam/odometry/odometry_options.h"

namespace stereo_fabmap_slam::odometry {

// What the keyframe bounds are checked on, at one moment since the last keyframe.
struct KeyframeMeasures {
  // Map points older than the last keyframe that are matched and inlier. The points the last
  // keyframe created are left out: many of them are fragile (a third may be gone 0.1 s later on
  // EuRoC MH01), so counting them would make the ratio depend on how soon after the keyframe the
  // next frame is tracked, i.e. on the frame rate. (ORB-SLAM's rule is similar: it compares only
  // points that more than one keyframe has seen.) A map's first keyframe inherits nothing, so
  // until the next one the ratio rule is idle and the other bounds apply (80 points, 0.25 m, 10
  // degrees, 1 s by default). Counting its own points instead brought the spike back: on MH01
  // the trajectory then depended on when the Backend's updates arrived (one manager against
  // every nodelet in its own process: 1.2-2.8 mm apart, against 0.07-0.11 mm without).
  int settled_points = 0;
  double translation = 0;   // [m]
  double rotation_deg = 0;  // [deg]
  double time = 0;          // [s]
};

struct KeyframePolicyInput {
  int tracked_points = 0;  // all map points matched and inlier in this frame
  // The most settled points tracked in a frame since the last keyframe (the keyframe's own
  // inliers at first): the ratio rule's reference.
  int reference_settled_points = 0;
  KeyframeMeasures now;
  // The measures extrapolated to the last camera frame before the next frame the tracker will
  // process, when it skips frames (a tracker that cannot keep up): a tracker that sees every
  // frame would take its keyframe there, so this frame, the last one before, takes it instead
  // of the first one after. Empty when no frame is skipped, or with no earlier tracked frame to
  // extrapolate from.
  std::optional<KeyframeMeasures> before_next_frame;
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
  // The first bound `measures` exceed (its name), or empty.
  std::string ExceededBound(const KeyframeMeasures& measures, int reference_settled_points) const;

  KeyframePolicyOptions options_;
};

}  // namespace stereo_fabmap_slam::odometry
