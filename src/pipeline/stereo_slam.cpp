#include "stereo_fabmap_slam/pipeline/stereo_slam.h"

#include <memory>
#include <stdexcept>
#include <utility>

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
                                   const relocalization::RelocalizerOptions& relocalizer_options,
                                   const backend::GlobalRefinementOptions& refinement_options) {
  if (!record_.frames().empty()) {
    throw std::logic_error("StereoSlam::EnableLoopClosing after the first frame");
  }
  mapping_ = MappingStage(bundle_adjustment_options_, pose_graph_options, clock_);
  mapping_.SetGlobalRefinement(refinement_options);
  place_.emplace(PlaceStage(std::move(detector), relocalizer_options, clock_), tracking_.camera());
  tracking_.SetRelocalizationOptions(relocalizer_options);
}

backend::GlobalRefinementSummary StereoSlam::RefineMap(
    const backend::GlobalRefinementOptions& options) {
  if (!place_) throw std::logic_error("StereoSlam::RefineMap without loop closing");
  Synchronize();
  const backend::GlobalRefinementSummary summary = mapping_.RefineGlobally(options);
  PublishSnapshot();
  return summary;
}

void StereoSlam::EnableConcurrentMapping(std::size_t queued_keyframes) {
  if (!record_.frames().empty()) {
    throw std::logic_error("StereoSlam::EnableConcurrentMapping after the first frame");
  }
  if (worker_) return;
  PublishSnapshot();
  worker_ = std::make_unique<SerialWorker>(queued_keyframes);
}

void StereoSlam::Synchronize() {
  if (!worker_) return;
  worker_->WaitIdle();
  TakeMappingResults();
}

std::shared_ptr<const MapState> StereoSlam::LatestMap() const {
  if (!worker_)
    return std::shared_ptr<const MapState>(std::shared_ptr<const MapState>(), &mapping_);
  std::lock_guard<std::mutex> lock(results_mutex_);
  return snapshot_;
}

void StereoSlam::PublishSnapshot() {
  auto snapshot = std::make_shared<const MapSnapshot>(MapSnapshot::Of(mapping_));
  std::lock_guard<std::mutex> lock(results_mutex_);
  snapshot_ = std::move(snapshot);
}

void StereoSlam::SetMode(SlamMode mode) {
  Synchronize();
  tracking_.SetMode(mode, !mapping_.empty());
  mapping_.SetMode(mode);
  if (worker_) PublishSnapshot();
}

MappedKeyframe StereoSlam::MapKeyframe(const map::Keyframe& keyframe) {
  MappedKeyframe mapped = mapping_.AddKeyframe(keyframe, tracking_.camera());
  if (place_) place_->stage()->AddKeyframe(keyframe, mapped);
  return mapped;
}

void StereoSlam::RunMappingJob(const map::Keyframe& keyframe, std::size_t frame_index) {
  MappingResult result;
  result.frame_index = frame_index;
  result.mapped = MapKeyframe(keyframe);
  if (place_ && result.mapped.in_map_graph) {
    result.place = place_->stage()->DetectLoop(result.mapped.keyframe_id);
    result.loop_pose_graph_ms =
        mapping_.ApplyLoopDetection(result.place->keyframe_id, result.place->detection.loop);
  }
  auto snapshot = std::make_shared<const MapSnapshot>(MapSnapshot::Of(mapping_));
  std::lock_guard<std::mutex> lock(results_mutex_);
  finished_.push_back(std::move(result));
  snapshot_ = std::move(snapshot);
}

void StereoSlam::TakeMappingResults() {
  std::vector<MappingResult> finished;
  {
    std::lock_guard<std::mutex> lock(results_mutex_);
    finished.swap(finished_);
  }
  for (MappingResult& result : finished) {
    tracking_.ApplyUpdate(result.mapped.update);
    record_.ApplyUpdate(result.mapped.update);
    record_.AddMappingTimes(result.frame_index, result.mapped.bundle_adjustment_ms,
                            result.mapped.pose_graph_ms + result.loop_pose_graph_ms,
                            result.place ? result.place->detection_ms : 0.0);
    if (result.place) record_.AddPlaceResult(std::move(*result.place));
  }
}

const FrameRecord* StereoSlam::ProcessFrame(double timestamp, const cv::Mat& left_raw,
                                            const cv::Mat& right_raw, int frames_skipped) {
  arrival_ += 1 + static_cast<std::uint64_t>(std::max(frames_skipped, 0));
  tracking_.input().OnPair(0);
  tracking_.input().CountSkipped(static_cast<std::uint64_t>(std::max(frames_skipped, 0)));
  TakeMappingResults();  // concurrent mapping: what the worker finished since the last frame
  const std::shared_ptr<const MapState> map = place_ ? LatestMap() : nullptr;
  TrackingOutput output = tracking_.Process({timestamp, left_raw, right_raw, arrival_}, map.get());
  last_events_ = output.events;
  if (!output.tracked) return nullptr;
  const odometry::TrackingResult& result = output.tracking;

  if (worker_ && !output.relocalization) {
    // The keyframe's mapping and loop detection go to the worker; this frame is recorded now.
    if (result.keyframe) {
      record_.AddKeyframe(result.keyframe->id, timestamp, result.keyframe->T_world_camera);
      const std::size_t frame_index = record_.frames().size();
      // The worker's own copy: cv::Mat copies share their pixels, which the front end's buffers
      // may be reused for while the worker reads them.
      map::Keyframe keyframe = *result.keyframe;
      keyframe.features.descriptors = keyframe.features.descriptors.clone();
      keyframe.place_descriptors = keyframe.place_descriptors.clone();
      worker_->Submit([this, keyframe = std::move(keyframe), frame_index] {
        RunMappingJob(keyframe, frame_index);
      });
    }
    record_.AddFrame(tracking_.RecordFrame(output, timestamp, nullptr));
    return &record_.frames().back();
  }
  // In order from here: a relocalization needs the map as every keyframe before it left it.
  Synchronize();

  // The keyframe's bundle adjustment, whose update the tracker follows before the next frame,
  // and (mapping mode) the pose graph; the place stage makes it a place.
  std::optional<MappedKeyframe> mapped;
  if (result.keyframe) {
    record_.AddKeyframe(result.keyframe->id, timestamp, result.keyframe->T_world_camera);
    mapped = MapKeyframe(*result.keyframe);
    tracking_.ApplyUpdate(mapped->update);
    record_.ApplyUpdate(mapped->update);
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
  if (worker_) PublishSnapshot();
  return &record_.frames().back();
}

MapFileAnswer StereoSlam::SaveMap(const std::string& path) const {
  if (!place_) throw std::logic_error("StereoSlam::SaveMap: loop closing is off");
  return place_->SaveMap(path, mapping_);
}

MapFileAnswer StereoSlam::LoadMap(const std::string& path) {
  if (!place_) throw std::logic_error("StereoSlam::LoadMap: loop closing is off");
  Synchronize();
  std::optional<LoadedMapFile> file;
  const MapFileAnswer answer = place_->LoadMap(path, &file);  // checks it all first
  if (!file) return answer;
  mapping_.Load(file->saved);
  tracking_.OnMapLoaded(file->loaded);
  for (const map::SavedKeyframe& keyframe : file->saved.keyframes) {
    record_.AddKeyframeTime(keyframe.keyframe.id, keyframe.keyframe.timestamp);
  }
  if (worker_) PublishSnapshot();
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
