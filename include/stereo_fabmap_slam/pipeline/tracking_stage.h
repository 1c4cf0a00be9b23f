#pragma once

#include <cstdint>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include <opencv2/core.hpp>

#include "stereo_fabmap_slam/camera/stereo_rectifier.h"
#include "stereo_fabmap_slam/map/keyframe_update.h"
#include "stereo_fabmap_slam/pipeline/frame_record.h"
#include "stereo_fabmap_slam/pipeline/input_monitor.h"
#include "stereo_fabmap_slam/pipeline/map_state.h"
#include "stereo_fabmap_slam/pipeline/place_stage.h"
#include "stereo_fabmap_slam/pipeline/relocalization_policy.h"
#include "stereo_fabmap_slam/pipeline/slam_mode.h"
#include "stereo_fabmap_slam/pipeline/stereo_front_end.h"

namespace stereo_fabmap_slam::pipeline {

// One stereo pair as a driver hands it over.
struct StereoPair {
  double timestamp = 0;  // [s]
  cv::Mat left, right;   // raw (unrectified) mono8 images of the calibrated size
  // Its place in the stream of pairs (1, 2, ...): pairs the driver passed over leave gaps, which
  // tell the tracker how far apart its frames are (Tracker::Track's frames_skipped).
  std::uint64_t arrival = 0;
};

struct TrackingOutput {
  bool tracked = false;  // false: the input monitor refused the pair (events say why)
  odometry::TrackingResult tracking;
  FrameTiming timing;
  std::vector<InputEvent> events;
  // Ask the place stage this, then hand its answer to OnRelocalization.
  std::optional<RelocalizationRequest> relocalization;
  // A relocalization was due or asked for, but the frame has no pose to find: why. When the
  // user had asked, `user` is the answer for the user.
  std::string relocalization_failure;
  std::optional<UserRelocalization> user;
};

// The tracking stage (the StereoTracker nodelet; run in order by StereoSlam): the input monitor,
// the front end (rectification, stereo features, tracking against the local map, keyframe
// decisions), and the relocalization policy that asks the place stage to find the camera in the
// map. Tracks in odom; knows the map only through MapState. The clock (milliseconds) is only
// read to fill the timings.
class TrackingStage {
 public:
  using Clock = StereoFrontEnd::Clock;

  // Relocalization is asked only with place recognition on (options.place_features), as
  // `relocalization` says (attempt_every_n_frames, confirm_distance: RelocalizationPolicy).
  TrackingStage(const FrontEndOptions& options, const camera::StereoRectifier& rectifier,
                const InputMonitorOptions& input,
                const relocalization::RelocalizerOptions& relocalization, Clock clock);
  // A stage whose camera is known later (a driver that reads the calibration from camera_info):
  // until Calibrate it refuses every pair (counted, and named by an event), while mode changes,
  // a loaded map and the relocalize service's requests are taken as always.
  TrackingStage(const FrontEndOptions& options, const InputMonitorOptions& input,
                const relocalization::RelocalizerOptions& relocalization, Clock clock);
  // The camera, once (std::logic_error for a second time), and its pose in odom at the first
  // frame (Tracker::SetStartPose): the nodelet's odom is the base's frame at the first frame, so
  // its camera starts at its mounting.
  void Calibrate(const camera::StereoRectifier& rectifier,
                 const Eigen::Isometry3d& T_odom_camera = Eigen::Isometry3d::Identity());
  bool calibrated() const { return front_end_.has_value(); }
  // Other recovery settings (before the first frame).
  void SetRelocalizationOptions(const relocalization::RelocalizerOptions& relocalization) {
    policy_ = RelocalizationPolicy(relocalization);
  }

  // One stereo pair: checked, tracked, and, if one is due, the relocalization request made.
  // `map`: what the mapping stage says of the map (null without loop closing).
  TrackingOutput Process(const StereoPair& pair, const MapState* map);
  RelocalizationOutcome OnRelocalization(const RelocalizationRequest& request,
                                         const RelocalizationAnswer& answer) {
    return policy_.OnAnswer(request, answer);
  }
  // The request could not be asked (RelocalizationPolicy::OnNoAnswer).
  RelocalizationOutcome OnNoRelocalization(const RelocalizationRequest& request,
                                           const std::string& reason) {
    return policy_.OnNoAnswer(request, reason);
  }
  // A pair the driver could not hand over (a message that is no image; `reason` says why):
  // counted as refused, and named by the output's event.
  TrackingOutput Refuse(const std::string& reason);
  // The record of a frame Process tracked, once its relocalization request (if any) was answered
  // (`answer`; null: none was asked, or it could not be asked): tracking's result, the attempt,
  // and, with a map to follow, whether and where the frame was on the map afterwards.
  FrameRecord RecordFrame(const TrackingOutput& output, double timestamp,
                          const RelocalizationAnswer* answer) const;

  // The bundle adjustment's corrections of the local map (MappedKeyframe::update).
  void ApplyUpdate(const map::KeyframeUpdate& update);
  // A map was loaded: the odometry goes on in a new local map, continuous in odom, numbered
  // above the map's keyframes and points, and is found in the map by relocalization. Before
  // Calibrate, the front end made then numbers from there.
  void OnMapLoaded(const LoadedMap& loaded);
  void SetMode(SlamMode mode, bool map_has_keyframes) { policy_.SetMode(mode, map_has_keyframes); }
  // The relocalize service: the next frame is found in the map; `reanchor` (mapping) corrects
  // map -> odom by it even while tracking is fine.
  void RequestRelocalization(bool reanchor) { policy_.RequestFromUser(reanchor); }
  void CancelRelocalizationRequest() { policy_.CancelUserRequest(); }

  // Whether the last frame had a pose in the map, and that pose in localization mode.
  bool on_map() const { return policy_.on_map(); }
  std::optional<Eigen::Isometry3d> T_map_camera() const { return policy_.T_map_camera(); }
  const RelocalizationPolicy& policy() const { return policy_; }

  // The driver's view of the input (single images, skipped pairs).
  InputMonitor& input() { return input_; }
  const InputMonitor& input() const { return input_; }
  // The front end and its camera; std::logic_error before Calibrate.
  const StereoFrontEnd& front_end() const;
  const geometry::StereoCamera& camera() const { return front_end().camera(); }
  bool places() const { return options_.place_features.has_value(); }

 private:
  FrontEndOptions options_;
  std::optional<StereoFrontEnd> front_end_;  // none before Calibrate
  InputMonitor input_;
  RelocalizationPolicy policy_;
  Clock clock_;
  bool map_followed_ = false;  // the last frame was tracked with places and a map (Process)
  // The ids a map loaded before Calibrate numbers the odometry's keyframes and points from.
  std::int64_t first_keyframe_id_ = 0, first_point_id_ = 0;
};

}  // namespace stereo_fabmap_slam::pipeline
