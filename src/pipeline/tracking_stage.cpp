#include "stereo_fabmap_slam/pipeline/tracking_stage.h"

#include <stdexcept>

namespace stereo_fabmap_slam::pipeline {

TrackingStage::TrackingStage(const FrontEndOptions& options,
                             const camera::StereoRectifier& rectifier,
                             const InputMonitorOptions& input,
                             const relocalization::RelocalizerOptions& relocalization, Clock clock)
    : TrackingStage(options, input, relocalization, std::move(clock)) {
  Calibrate(rectifier);
}

TrackingStage::TrackingStage(const FrontEndOptions& options, const InputMonitorOptions& input,
                             const relocalization::RelocalizerOptions& relocalization, Clock clock)
    : options_(options), input_(input), policy_(relocalization), clock_(std::move(clock)) {}

void TrackingStage::Calibrate(const camera::StereoRectifier& rectifier,
                              const Eigen::Isometry3d& T_odom_camera) {
  if (front_end_) throw std::logic_error("TrackingStage::Calibrate: calibrated already");
  front_end_.emplace(options_, rectifier, clock_);
  front_end_->SetStartPose(T_odom_camera);
  front_end_->SkipIdsBelow(first_keyframe_id_, first_point_id_);
  input_.SetImageSize(rectifier.camera().size);
}

const StereoFrontEnd& TrackingStage::front_end() const {
  if (!front_end_) throw std::logic_error("TrackingStage: no calibration yet");
  return *front_end_;
}

void TrackingStage::ApplyUpdate(const map::KeyframeUpdate& update) {
  // Before Calibrate the front end made no keyframe: an update is of another run's.
  if (front_end_) front_end_->ApplyUpdate(update);
}

TrackingOutput TrackingStage::Process(const StereoPair& pair, const MapState* map) {
  TrackingOutput output;
  InputMonitor::Verdict verdict =
      input_.CheckPair(pair.timestamp, pair.left, pair.right, pair.arrival);
  output.events = std::move(verdict.events);
  if (!verdict.track) return output;
  if (verdict.reset) {
    front_end_->Reset();
    policy_.OnReset();
  }
  // The monitor refuses every pair until Calibrate gave it the image size.
  FrontEndOutput tracked =
      front_end_->Process(pair.timestamp, pair.left, pair.right, verdict.frames_skipped);
  output.tracked = true;
  output.timing = tracked.timing;
  output.tracking = std::move(tracked.tracking);
  map_followed_ = places() && map != nullptr;
  if (!map_followed_) return output;

  const odometry::TrackingResult& result = output.tracking;
  const RelocalizationPolicy::Decision decision =
      policy_.Decide(result, !map->empty(),
                     result.reference_keyframe >= 0 && map->InMap(result.reference_keyframe));
  if (!decision.failure.empty()) {
    output.relocalization_failure = decision.failure;
    if (decision.from_user) output.user = policy_.FailUserRequest(decision.failure);
  }
  if (!decision.ask) return output;
  RelocalizationRequest request;
  const double start = clock_();
  request.place_descriptors =
      result.keyframe ? result.keyframe->place_descriptors : front_end_->DescribeLastFrame();
  request.describe_ms = clock_() - start;
  request.timestamp = pair.timestamp;
  request.features = std::move(tracked.features);
  request.scope = decision.scope;
  request.reference_keyframe = result.reference_keyframe;
  request.T_reference_camera = result.T_keyframe_camera;
  request.T_odom_camera = result.T_world_camera;
  request.add_edge = decision.add_edge;
  request.expected_T_map_camera = decision.expected_T_map_camera;
  request.from_user = decision.from_user;
  output.relocalization = std::move(request);
  return output;
}

TrackingOutput TrackingStage::Refuse(const std::string& reason) {
  input_.CountRefused();
  TrackingOutput output;
  output.events.push_back({InputEvent::Kind::kUnreadable, reason + "; frame skipped", true, true});
  return output;
}

FrameRecord TrackingStage::RecordFrame(const TrackingOutput& output, double timestamp,
                                       const RelocalizationAnswer* answer) const {
  const odometry::TrackingResult& result = output.tracking;
  FrameRecord record;
  record.timestamp = timestamp;
  record.timing = output.timing;
  record.state = result.state;
  record.T_world_camera = result.T_world_camera;
  record.reference_keyframe = result.reference_keyframe;
  record.T_keyframe_camera = result.T_keyframe_camera;
  record.is_keyframe = result.keyframe.has_value();
  record.inliers = result.inliers;
  record.note = result.reason;
  if (answer != nullptr) {
    RecordRelocalization(*answer, &record);
    if (answer->result.success() && policy_.mode() == SlamMode::kMapping && policy_.recovering()) {
      // A recovery's success that left the segment off the map (RelocalizationPolicy): the
      // candidate, a user's check of the view near it, or a view from elsewhere that disagrees
      // with it (the new candidate); not yet a relocalization.
      record.relocalized = false;
      *record.relocalization += answer->agrees.has_value()
                                    ? "; disagrees with the candidate, replaces it"
                                    : "; a candidate, to be confirmed";
    } else if (answer->agrees.value_or(false)) {
      *record.relocalization += "; agrees with the candidate";
    }
  }
  // Without a map to be on (no loop closing) every frame counts as on it: the map is the odometry.
  if (map_followed_) {
    record.on_map = policy_.on_map();
    record.T_map_camera = policy_.T_map_camera();
  }
  return record;
}

void TrackingStage::OnMapLoaded(const LoadedMap& loaded) {
  // This run's keyframes so far may share the map's ids: a new local map, numbered above it.
  first_keyframe_id_ = loaded.next_keyframe_id;
  first_point_id_ = loaded.next_point_id;
  if (front_end_) {
    front_end_->StartNewLocalMap();
    front_end_->SkipIdsBelow(loaded.next_keyframe_id, loaded.next_point_id);
  }
  policy_.OnMapLoaded();
}

}  // namespace stereo_fabmap_slam::pipeline
