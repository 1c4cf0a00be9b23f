#include "stereo_fabmap_slam/pipeline/stereo_slam.h"

#include <stdexcept>

#include "stereo_fabmap_slam/map/map_file.h"

namespace stereo_fabmap_slam::pipeline {
namespace {

InputMonitorOptions MonitorOptions(const FrontEndOptions& options) {
  InputMonitorOptions monitor;
  monitor.max_prediction_gap = options.tracker.max_prediction_gap;
  return monitor;
}

}  // namespace

StereoSlam::StereoSlam(const FrontEndOptions& front_end_options,
                       const backend::BundleAdjustmentOptions& bundle_adjustment_options,
                       const camera::StereoRectifier& rectifier, Clock clock)
    : clock_(clock),
      tracking_(front_end_options, rectifier, MonitorOptions(front_end_options),
                relocalization::RelocalizerOptions(), clock),
      mapping_(bundle_adjustment_options, backend::PoseGraphOptions(), clock),
      bundle_adjustment_options_(bundle_adjustment_options) {}

void StereoSlam::EnableLoopClosing(place_recognition::LoopDetector detector,
                                   const backend::PoseGraphOptions& pose_graph_options,
                                   const relocalization::RelocalizerOptions& relocalizer_options) {
  if (!record_.frames().empty()) {
    throw std::logic_error("StereoSlam::EnableLoopClosing after the first frame");
  }
  mapping_ = MappingStage(bundle_adjustment_options_, pose_graph_options, clock_);
  place_.emplace(PlaceStage(std::move(detector), relocalizer_options, clock_), tracking_.camera());
  tracking_.SetRelocalizationOptions(relocalizer_options);
}

void StereoSlam::SetMode(SlamMode mode) {
  tracking_.SetMode(mode, !mapping_.empty());
  mapping_.SetMode(mode);
}

const FrameRecord* StereoSlam::ProcessFrame(double timestamp, const cv::Mat& left_raw,
                                            const cv::Mat& right_raw, int frames_skipped) {
  arrival_ += 1 + static_cast<std::uint64_t>(std::max(frames_skipped, 0));
  tracking_.input().OnPair(0);
  tracking_.input().CountSkipped(static_cast<std::uint64_t>(std::max(frames_skipped, 0)));
  TrackingOutput output =
      tracking_.Process({timestamp, left_raw, right_raw, arrival_}, map_state());
  last_events_ = output.events;
  if (!output.tracked) return nullptr;
  const odometry::TrackingResult& result = output.tracking;

  // The keyframe's bundle adjustment, whose update the tracker follows before the next frame,
  // and (mapping mode) the pose graph; the place stage makes it a place.
  std::optional<MappedKeyframe> mapped;
  if (result.keyframe) {
    record_.AddKeyframe(result.keyframe->id, timestamp, result.keyframe->T_world_camera);
    mapped = mapping_.AddKeyframe(*result.keyframe, tracking_.camera());
    tracking_.ApplyUpdate(mapped->update);
    record_.ApplyUpdate(mapped->update);
    if (place_) place_->stage()->AddKeyframe(*result.keyframe, *mapped);
  }
  // Before loop detection: after a loss, finding the frame in the map is relocalization's job,
  // and the loop detection of the same keyframe then adds a loop within one map.
  std::optional<RelocalizationAnswer> answer;
  double relocalization_edge_ms = 0;
  if (place_ && output.relocalization) {
    answer = place_->Relocalize(*output.relocalization, mapping_);
    if (answer->edge) {
      relocalization_edge_ms =
          mapping_.AddEdge(*answer->edge, backend::PoseGraphEdgeType::kRelocalization);
    }
    const RelocalizationOutcome outcome =
        tracking_.OnRelocalization(*output.relocalization, *answer);
    if (outcome.T_map_odom) mapping_.SetLocalizationCorrection(*outcome.T_map_odom);
  }
  FrameRecord record = tracking_.RecordFrame(output, timestamp, answer ? &*answer : nullptr);
  if (mapped) {
    record.timing.bundle_adjustment_ms = mapped->bundle_adjustment_ms;
    record.timing.pose_graph_ms += mapped->pose_graph_ms;
  }
  record.timing.pose_graph_ms += relocalization_edge_ms;
  if (place_ && mapped && mapped->in_map_graph) {
    PlaceResult place = place_->stage()->DetectLoop(mapped->keyframe_id);
    record.timing.loop_detection_ms = place.detection_ms;
    record.timing.pose_graph_ms +=
        mapping_.ApplyLoopDetection(place.keyframe_id, place.detection.loop);
    record_.AddPlaceResult(std::move(place));
  }
  record_.AddFrame(std::move(record));
  return &record_.frames().back();
}

MapFileAnswer StereoSlam::SaveMap(const std::string& path) const {
  if (!place_) throw std::logic_error("StereoSlam::SaveMap: loop closing is off");
  return place_->SaveMap(path, mapping_);
}

MapFileAnswer StereoSlam::LoadMap(const std::string& path) {
  if (!place_) throw std::logic_error("StereoSlam::LoadMap: loop closing is off");
  std::optional<LoadedMapFile> file;
  const MapFileAnswer answer = place_->LoadMap(path, &file);  // checks it all first
  if (!file) return answer;
  mapping_.Load(file->saved);
  tracking_.OnMapLoaded(file->loaded);
  for (const map::SavedKeyframe& keyframe : file->saved.keyframes) {
    record_.AddKeyframeTime(keyframe.keyframe.id, keyframe.keyframe.timestamp);
  }
  return answer;
}

RelocalizationOutput StereoSlam::Relocalize(const cv::Mat& left_raw,
                                            const cv::Mat& right_raw) const {
  if (!place_) throw std::logic_error("StereoSlam::Relocalize: loop closing is off");
  const double start = clock_();
  RelocalizationRequest request;
  request.features = tracking_.front_end().Extract(left_raw, right_raw, &request.place_descriptors);
  RelocalizationOutput output;
  output.extraction_ms = clock_() - start;
  const RelocalizationAnswer answer = place_->Relocalize(request, mapping_);
  output.result = answer.result;
  output.T_map_camera = answer.T_map_camera;
  output.ms = answer.ms;
  return output;
}

}  // namespace stereo_fabmap_slam::pipeline
