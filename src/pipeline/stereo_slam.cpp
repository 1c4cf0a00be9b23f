#include "stereo_fabmap_slam/pipeline/stereo_slam.h"

#include <algorithm>
#include <stdexcept>

#include "stereo_fabmap_slam/geometry/relative_pose_error.h"

namespace stereo_fabmap_slam::pipeline {

StereoSlam::StereoSlam(const FrontEndOptions& front_end_options,
                       const backend::BundleAdjustmentOptions& bundle_adjustment_options,
                       const camera::StereoRectifier& rectifier, Clock clock)
    : clock_(clock),
      front_end_(front_end_options, rectifier, clock),
      backend_(bundle_adjustment_options, rectifier.camera(), clock) {}

const FrameRecord& StereoSlam::ProcessFrame(double timestamp, const cv::Mat& left_raw,
                                            const cv::Mat& right_raw, int frames_skipped) {
  FrontEndOutput output = front_end_.Process(timestamp, left_raw, right_raw, frames_skipped);
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
  const bool mapping = loop_closing_ && mode_ == SlamMode::kMapping;
  if (result.keyframe) {
    keyframe_times_[result.keyframe->id] = timestamp;
    const BackendOutput adjusted = backend_.Process(*result.keyframe);
    front_end_.ApplyUpdate(adjusted.update);
    record.timing.bundle_adjustment_ms = adjusted.bundle_adjustment_ms;
    if (mapping) {
      loop_closing_->AddKeyframe(*result.keyframe, adjusted.update);
      if (anchor_ < 0) anchor_ = result.keyframe->id;
    }
  }
  if (loop_closing_) {
    // Before loop detection: after a loss, finding the frame in the map is relocalization's job,
    // and the loop detection of the same keyframe then adds a loop within one map.
    if (mapping) {
      RecoverIntoMap(output, &record);
    } else {
      Localize(output, &record);
    }
  }
  if (mapping && result.keyframe) {
    LoopClosingOutput closing = loop_closing_->DetectLoop(result.keyframe->id);
    record.timing.loop_detection_ms = closing.detection_ms;
    record.timing.pose_graph_ms += closing.pose_graph_ms;
    record.loop_detection = std::move(closing.detection);
  }
  frames_.push_back(std::move(record));
  return frames_.back();
}

RelocalizationOutput StereoSlam::RelocalizeFrame(
    const FrontEndOutput& output, const relocalization::Relocalizer::KeyframeFilter& allowed) {
  const double start = clock_();
  const cv::Mat descriptors = output.tracking.keyframe ? output.tracking.keyframe->place_descriptors
                                                       : front_end_.DescribeLastFrame();
  const double describe_ms = clock_() - start;
  RelocalizationOutput relocalized =
      relocalization_->Process(output.features, descriptors, *loop_closing_, allowed);
  relocalized.ms += describe_ms;
  return relocalized;
}

void StereoSlam::RecoverIntoMap(const FrontEndOutput& output, FrameRecord* record) {
  const odometry::TrackingResult& result = output.tracking;
  const backend::PoseGraph& graph = loop_closing_->pose_graph();
  const std::int64_t reference = result.reference_keyframe;
  if (reference < 0 || !graph.Contains(reference)) {
    record->on_map = false;  // lost before any keyframe: nothing to attach a relocalization to
    return;
  }
  if (graph.Connected(reference, anchor_)) {
    frames_off_map_ = 0;
    return;
  }
  record->on_map = false;
  if (frames_off_map_++ % relocalization_->options().attempt_every_n_frames != 0) return;
  RelocalizationOutput relocalized =
      RelocalizeFrame(output, [&](const map::StoredKeyframe& keyframe) {
        return graph.Connected(keyframe.keyframe.id, anchor_);
      });
  if (relocalized.result.success()) {
    // The edge joins the frame's reference keyframe (its piece of odometry) to the match.
    map::LoopEdge edge;
    edge.match_id = relocalized.result.keyframe_id;
    edge.query_id = reference;
    edge.T_match_query = relocalized.result.T_keyframe_camera * result.T_keyframe_camera.inverse();
    edge.information =
        geometry::DiagonalPoseInformation(relocalization_->options().translation_sigma,
                                          relocalization_->options().rotation_sigma_deg);
    edge.inliers = relocalized.result.inliers;
    edge.probability = relocalized.result.probability;
    record->timing.pose_graph_ms += loop_closing_->AddRelocalization(edge);
    record->on_map = true;
    frames_off_map_ = 0;
  }
  record->timing.relocalization_ms = relocalized.ms;
  record->relocalization = std::move(relocalized);
}

void StereoSlam::Localize(const FrontEndOutput& output, FrameRecord* record) {
  const odometry::TrackingResult& result = output.tracking;
  // A loss that starts a new piece breaks the odometry: the old map -> odom no longer holds. A
  // lost frame whose map the tracker kept has no pose, but the odometry goes on unbroken.
  if (result.state == odometry::TrackingState::kLost && !result.map_kept) localized_ = false;
  if (result.map_kept) {
    record->on_map = false;  // no pose to give, in the map or in odom
    return;
  }
  const bool attempt =
      localized_ ? result.keyframe.has_value()
                 : frames_off_map_++ % relocalization_->options().attempt_every_n_frames == 0;
  if (attempt && result.state != odometry::TrackingState::kLost && !loop_closing_->empty()) {
    RelocalizationOutput relocalized =
        RelocalizeFrame(output, [](const map::StoredKeyframe&) { return true; });
    if (relocalized.result.success()) {
      T_map_odom_ = relocalized.T_map_camera * result.T_world_camera.inverse();
      localized_ = true;
      frames_off_map_ = 0;
    }
    record->timing.relocalization_ms = relocalized.ms;
    record->relocalization = std::move(relocalized);
  }
  record->on_map = localized_;
  if (localized_) record->T_map_camera = T_map_odom_ * result.T_world_camera;
}

void StereoSlam::SaveMap(const std::string& path) const {
  if (!loop_closing_) throw std::logic_error("StereoSlam::SaveMap: loop closing is off");
  map::SaveMapFile(path, loop_closing_->Save(front_end_.camera()));
}

void StereoSlam::LoadMap(const std::string& path) {
  if (!loop_closing_) throw std::logic_error("StereoSlam::LoadMap: loop closing is off");
  const map::SavedMap saved = map::LoadMapFile(path);
  loop_closing_->Load(saved, front_end_.camera());
  std::int64_t next_keyframe = 0, next_point = 0;
  for (const map::SavedKeyframe& keyframe : saved.keyframes) {
    keyframe_times_[keyframe.keyframe.id] = keyframe.keyframe.timestamp;
    next_keyframe = std::max(next_keyframe, keyframe.keyframe.id + 1);
    for (const std::int64_t point : keyframe.keyframe.map_point_ids) {
      next_point = std::max(next_point, point + 1);
    }
  }
  // A new piece of odometry, numbered above the map: this run's keyframes so far (if any) may
  // share the map's ids.
  if (!frames_.empty()) front_end_.StartNewMap();
  front_end_.SkipIdsBelow(next_keyframe, next_point);
  anchor_ = saved.keyframes.empty() ? -1 : saved.keyframes.front().keyframe.id;
  localized_ = false;
  frames_off_map_ = 0;
}

RelocalizationOutput StereoSlam::Relocalize(const cv::Mat& left_raw,
                                            const cv::Mat& right_raw) const {
  if (!loop_closing_) throw std::logic_error("StereoSlam::Relocalize: loop closing is off");
  const double start = clock_();
  cv::Mat descriptors;
  const features::StereoFeatures features = front_end_.Extract(left_raw, right_raw, &descriptors);
  const double extract_ms = clock_() - start;
  RelocalizationOutput relocalized = relocalization_->Process(
      features, descriptors, *loop_closing_, [](const map::StoredKeyframe&) { return true; });
  relocalized.extraction_ms = extract_ms;
  return relocalized;
}

io::Trajectory StereoSlam::OdometryTrajectory() const {
  const std::map<std::int64_t, Eigen::Isometry3d> keyframes = backend_.KeyframePoses();
  io::Trajectory trajectory;
  for (const FrameRecord& frame : frames_) {
    // A lost frame without a keyframe to refer to has no pose, only the motion model's guess.
    if (frame.state == odometry::TrackingState::kLost && frame.reference_keyframe < 0) continue;
    const auto keyframe = keyframes.find(frame.reference_keyframe);
    trajectory.push_back({frame.timestamp, keyframe == keyframes.end()
                                               ? frame.T_world_camera
                                               : keyframe->second * frame.T_keyframe_camera});
  }
  return trajectory;
}

void StereoSlam::EnableLoopClosing(place_recognition::LoopDetector detector,
                                   const backend::PoseGraphOptions& pose_graph_options,
                                   const relocalization::RelocalizerOptions& relocalizer_options) {
  loop_closing_.emplace(std::move(detector), pose_graph_options, clock_);
  relocalization_.emplace(relocalizer_options, front_end_.camera(), front_end_.descriptor_norm(),
                          front_end_.max_match_distance(), clock_);
}

io::Trajectory StereoSlam::MapTrajectory() const {
  if (!loop_closing_) return OdometryTrajectory();
  const backend::PoseGraph& graph = loop_closing_->pose_graph();
  io::Trajectory trajectory;
  for (const FrameRecord& frame : frames_) {
    if (frame.T_map_camera) {
      trajectory.push_back({frame.timestamp, *frame.T_map_camera});  // localization mode
    } else if (frame.reference_keyframe >= 0 && graph.Contains(frame.reference_keyframe) &&
               graph.Connected(frame.reference_keyframe, anchor_)) {
      trajectory.push_back(
          {frame.timestamp, graph.MapPose(frame.reference_keyframe) * frame.T_keyframe_camera});
    }
  }
  return trajectory;
}

io::Trajectory StereoSlam::KeyframeTrajectory() const {
  io::Trajectory trajectory;
  const std::map<std::int64_t, Eigen::Isometry3d> poses =
      loop_closing_ ? loop_closing_->pose_graph().MapPoses() : backend_.KeyframePoses();
  for (const auto& [id, pose] : poses) {
    trajectory.push_back({keyframe_times_.at(id), pose});
  }
  return trajectory;
}

}  // namespace stereo_fabmap_slam::pipeline
