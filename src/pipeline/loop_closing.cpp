#include "stereo_fabmap_slam/pipeline/loop_closing.h"

#include "stereo_fabmap_slam/place_recognition/chow_liu_tree.h"
#include "stereo_fabmap_slam/place_recognition/place_database.h"

namespace stereo_fabmap_slam::pipeline {

LoopClosing::LoopClosing(place_recognition::LoopDetector detector,
                         const backend::PoseGraphOptions& pose_graph_options, Clock clock)
    : detector_(std::move(detector)), pose_graph_(pose_graph_options), clock_(std::move(clock)) {}

place_recognition::LoopDetector LoopClosing::LoadDetector(
    const place_recognition::PlaceRecognitionOptions& options,
    const place_recognition::LoopDetectorOptions& detector_options,
    const geometry::StereoCamera& camera, int descriptor_norm, double max_descriptor_distance) {
  const std::string directory = options.vocabulary_directory;
  place_recognition::PlaceDatabase training_places;
  if (options.fabmap.new_place_model == place_recognition::NewPlaceModel::kSampling) {
    training_places = place_recognition::PlaceDatabase::Load(directory + "/training_places.bin");
  }
  place_recognition::FabMap fabmap(
      place_recognition::ChowLiuTree::Load(directory + "/chow_liu_tree.bin"), options.fabmap,
      std::move(training_places));
  return place_recognition::LoopDetector(
      detector_options, place_recognition::Vocabulary::Load(directory + "/vocabulary.bin"),
      std::move(fabmap), camera, descriptor_norm, max_descriptor_distance);
}

void LoopClosing::AddKeyframe(const map::Keyframe& keyframe, const map::KeyframeUpdate& update) {
  map::Keyframe adjusted = keyframe;
  for (const auto& [id, pose] : update.keyframe_poses) {
    if (id == keyframe.id) {
      adjusted.T_world_camera = pose;
    } else {
      if (pose_graph_.Contains(id)) pose_graph_.UpdateOdometryPose(id, pose);
      detector_.UpdatePose(id, pose);
    }
  }
  pose_graph_.AddKeyframe(adjusted.id, adjusted.T_world_camera, adjusted.starts_new_map);
  detector_.Add(std::move(adjusted));
}

LoopClosingOutput LoopClosing::DetectLoop(std::int64_t keyframe_id) {
  LoopClosingOutput output;
  double start = clock_();
  output.detection = detector_.DetectStored(keyframe_id);
  output.detection_ms = clock_() - start;
  if (output.detection.loop) {
    start = clock_();
    pose_graph_.AddLoop(*output.detection.loop);
    pose_graph_.Optimize();
    output.optimised = true;
    output.pose_graph_ms = clock_() - start;
  }
  return output;
}

double LoopClosing::AddRelocalization(const map::LoopEdge& edge) {
  const double start = clock_();
  pose_graph_.AddLoop(edge, backend::PoseGraphEdgeType::kRelocalization);
  pose_graph_.Optimize();
  return clock_() - start;
}

}  // namespace stereo_fabmap_slam::pipeline
