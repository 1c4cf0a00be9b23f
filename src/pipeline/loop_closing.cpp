#include "stereo_fabmap_slam/pipeline/loop_closing.h"

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "stereo_fabmap_slam/io/input_error.h"

#include "stereo_fabmap_slam/place_recognition/chow_liu_tree.h"
#include "stereo_fabmap_slam/place_recognition/detector_model.h"
#include "stereo_fabmap_slam/place_recognition/place_database.h"

namespace stereo_fabmap_slam::pipeline {

LoopClosing::LoopClosing(place_recognition::LoopDetector detector,
                         const backend::PoseGraphOptions& pose_graph_options, Clock clock)
    : detector_(std::move(detector)),
      pose_graph_options_(pose_graph_options),
      pose_graph_(pose_graph_options),
      clock_(std::move(clock)) {}

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
      place_recognition::ChowLiuTree::Load(directory + "/chow_liu_tree.bin"),
      place_recognition::ResolveDetectorModel(options.fabmap, directory),
      std::move(training_places));
  return place_recognition::LoopDetector(
      detector_options, place_recognition::Vocabulary::Load(directory + "/vocabulary.bin"),
      std::move(fabmap), camera, descriptor_norm, max_descriptor_distance);
}

void LoopClosing::AddKeyframe(const map::Keyframe& keyframe, const map::KeyframeUpdate& update) {
  map::Keyframe adjusted = keyframe;
  for (const auto& [id, pose] : update.keyframe_poses) {
    if (id < loaded_below_) continue;  // a loaded map's, or this run's from before the load
    if (id == keyframe.id) {
      adjusted.T_world_camera = pose;
    } else {
      if (pose_graph_.Contains(id)) pose_graph_.UpdateOdometryPose(id, pose);
      detector_.UpdatePose(id, pose);
    }
  }
  adjusted.starts_new_map = adjusted.starts_new_map || next_starts_new_map_;
  next_starts_new_map_ = false;
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

map::SavedMap LoopClosing::Save(const geometry::StereoCamera& camera) const {
  map::SavedMap saved;
  saved.vocabulary_fingerprint = detector_.vocabulary_fingerprint();
  saved.camera = camera;
  for (const auto& [id, stored] : detector_.database().keyframes()) {
    saved.keyframes.push_back({stored.keyframe, stored.words, pose_graph_.MapPose(id)});
  }
  for (const backend::PoseGraphEdge& edge : pose_graph_.Edges()) {
    if (edge.type == backend::PoseGraphEdgeType::kOdometry) continue;
    map::SavedEdge saved_edge;
    saved_edge.edge.match_id = edge.from;
    saved_edge.edge.query_id = edge.to;
    saved_edge.edge.T_match_query = edge.T_from_to;
    saved_edge.edge.information = edge.information;
    saved_edge.relocalization = edge.type == backend::PoseGraphEdgeType::kRelocalization;
    saved.edges.push_back(saved_edge);
  }
  return saved;
}

void LoopClosing::Load(const map::SavedMap& saved, const geometry::StereoCamera& camera) {
  CheckFits(saved, detector_, camera);
  // Built aside and swapped in, so that a failure leaves the running map as it was.
  place_recognition::LoopDetector detector = RestoreDetector(saved, detector_);
  backend::PoseGraph graph = RestorePoseGraph(saved, pose_graph_options_);
  detector_ = std::move(detector);
  pose_graph_ = std::move(graph);
  next_starts_new_map_ = true;
  for (const map::SavedKeyframe& keyframe : saved.keyframes) {
    loaded_below_ = std::max(loaded_below_, keyframe.keyframe.id + 1);
  }
}

void LoopClosing::CheckFits(const map::SavedMap& saved,
                            const place_recognition::LoopDetector& detector,
                            const geometry::StereoCamera& camera) {
  if (saved.vocabulary_fingerprint != detector.vocabulary_fingerprint()) {
    throw io::InputError(
        "the map was made with another vocabulary (its words would mean other things here)");
  }
  const geometry::StereoCamera& c = saved.camera;
  const auto near = [](double a, double b) { return std::abs(a - b) <= 1e-6 * std::abs(b); };
  if (c.size != camera.size || !near(c.fx, camera.fx) || !near(c.fy, camera.fy) ||
      !near(c.cx, camera.cx) || !near(c.cy, camera.cy) || !near(c.baseline, camera.baseline)) {
    char text[256];
    std::snprintf(text, sizeof(text),
                  "the map was made with another camera (%dx%d, f %.2f, baseline %.4f m; this "
                  "one %dx%d, f %.2f, baseline %.4f m)",
                  c.size.width, c.size.height, c.fx, c.baseline, camera.size.width,
                  camera.size.height, camera.fx, camera.baseline);
    throw io::InputError(text);
  }
}

place_recognition::LoopDetector LoopClosing::RestoreDetector(
    const map::SavedMap& saved, const place_recognition::LoopDetector& detector) {
  place_recognition::LoopDetector restored = detector.WithoutKeyframes();
  try {
    for (const map::SavedKeyframe& keyframe : saved.keyframes) {
      restored.Add(keyframe.keyframe, keyframe.words);
    }
  } catch (const std::invalid_argument& error) {
    throw io::InputError(std::string("the map is inconsistent: ") + error.what());
  }
  return restored;
}

backend::PoseGraph LoopClosing::RestorePoseGraph(const map::SavedMap& saved,
                                                 const backend::PoseGraphOptions& options) {
  backend::PoseGraph graph(options);
  try {
    for (const map::SavedKeyframe& keyframe : saved.keyframes) {
      graph.AddKeyframe(keyframe.keyframe.id, keyframe.keyframe.T_world_camera,
                        keyframe.keyframe.starts_new_map);
    }
    for (const map::SavedEdge& edge : saved.edges) {
      graph.AddLoop(edge.edge, edge.relocalization ? backend::PoseGraphEdgeType::kRelocalization
                                                   : backend::PoseGraphEdgeType::kLoop);
    }
    for (const map::SavedKeyframe& keyframe : saved.keyframes) {
      graph.RestoreMapPose(keyframe.keyframe.id, keyframe.T_map_camera);
    }
  } catch (const std::invalid_argument& error) {
    throw io::InputError(std::string("the map is inconsistent: ") + error.what());
  }
  return graph;
}

double LoopClosing::AddRelocalization(const map::LoopEdge& edge) {
  const double start = clock_();
  pose_graph_.AddLoop(edge, backend::PoseGraphEdgeType::kRelocalization);
  pose_graph_.Optimize();
  return clock_() - start;
}

}  // namespace stereo_fabmap_slam::pipeline
