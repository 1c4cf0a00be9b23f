#include "stereo_fabmap_slam/pipeline/place_stage.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <stdexcept>

#include "stereo_fabmap_slam/geometry/relative_pose_error.h"
#include "stereo_fabmap_slam/io/input_error.h"
#include "stereo_fabmap_slam/place_recognition/chow_liu_tree.h"
#include "stereo_fabmap_slam/place_recognition/detector_model.h"
#include "stereo_fabmap_slam/place_recognition/place_database.h"

namespace stereo_fabmap_slam::pipeline {

PlaceStage::PlaceStage(place_recognition::LoopDetector detector,
                       const relocalization::RelocalizerOptions& relocalizer_options, Clock clock)
    : detector_(std::move(detector)),
      relocalizer_(relocalizer_options, detector_.verifier().camera(),
                   detector_.verifier().descriptor_norm(),
                   detector_.verifier().max_descriptor_distance()),
      clock_(std::move(clock)) {}

place_recognition::LoopDetector PlaceStage::LoadDetector(
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

void PlaceStage::AddKeyframe(const map::Keyframe& keyframe, const MappedKeyframe& mapped) {
  map::Keyframe adjusted = keyframe;
  for (const auto& [id, pose] : mapped.update.keyframe_poses) {
    if (id == keyframe.id) {
      adjusted.T_world_camera = pose;
    } else {
      detector_.UpdatePose(id, pose);
    }
  }
  if (!mapped.in_map_graph) return;
  adjusted.starts_new_segment = mapped.starts_new_segment;
  detector_.Add(std::move(adjusted));
}

PlaceResult PlaceStage::DetectLoop(std::int64_t keyframe_id) {
  PlaceResult result;
  const double start = clock_();
  result.keyframe_id = keyframe_id;
  result.timestamp = detector_.database().Get(keyframe_id).keyframe.timestamp;
  result.detection = detector_.DetectStored(keyframe_id);
  result.detection_ms = clock_() - start;
  return result;
}

std::string LoopQueryRefusal(const LoopQuery& query, const PlaceStage* stage) {
  const auto holds = [&](std::int64_t id) {
    return stage != nullptr && stage->detector().database().Contains(id);
  };
  if (query.stored_id >= 0) {
    return holds(query.stored_id)
               ? ""
               : "keyframe " + std::to_string(query.stored_id) + " is not in the map";
  }
  if (query.keyframe.place_descriptors.empty() || query.keyframe.features.size() == 0) {
    return "the keyframe has no descriptors";
  }
  if (query.add && holds(query.keyframe.id)) {
    return "keyframe " + std::to_string(query.keyframe.id) + " is in the map already";
  }
  return "";
}

place_recognition::LoopDetection PlaceStage::Answer(const LoopQuery& query) {
  const std::string refusal = LoopQueryRefusal(query, this);
  if (!refusal.empty()) throw std::invalid_argument(refusal);
  if (query.stored_id >= 0) return DetectLoop(query.stored_id).detection;
  return detector_.Process(query.keyframe, query.add);
}

RelocalizationAnswer PlaceStage::Relocalize(const RelocalizationRequest& request,
                                            const MapState& map) const {
  RelocalizationAnswer answer;
  const double start = clock_();
  const bool in_map_only = request.scope == RelocalizationRequest::Scope::kMap;
  if (in_map_only && request.reference_keyframe >= 0 && map.InMap(request.reference_keyframe)) {
    answer.already_joined = true;
    answer.result.reason = "the frame's segment is in the map already";
    return answer;
  }
  // Recovery: ranked by the chain of the frame's segment so far, as its loops are.
  const map::KeyframeDatabase& database = detector_.database();
  const std::int64_t segment = in_map_only && request.reference_keyframe >= 0 &&
                                       database.Contains(request.reference_keyframe)
                                   ? database.Get(request.reference_keyframe).segment
                                   : -1;
  answer.result = relocalizer_.Relocalize(
      request.features, detector_.Words(request.place_descriptors), detector_,
      [&](const map::StoredKeyframe& keyframe) {
        return !in_map_only || map.InMap(keyframe.keyframe.id);
      },
      segment);
  const relocalization::Relocalization& found = answer.result;
  if (found.success()) {
    // A keyframe too new for the map's last word (the nodelets' map_graph follows the bundle
    // adjustment) is placed by its odometry pose and map -> odom.
    answer.map_pose_known = map.Contains(found.keyframe_id) || !map.empty();
    const Eigen::Isometry3d T_map_keyframe =
        map.Contains(found.keyframe_id)
            ? map.MapPose(found.keyframe_id)
            : map.MapToOdom() * detector_.database().Get(found.keyframe_id).keyframe.T_world_camera;
    answer.T_map_camera = T_map_keyframe * found.T_keyframe_camera;
    if (request.expected_T_map_camera) {
      const Eigen::Isometry3d difference =
          request.expected_T_map_camera->inverse() * answer.T_map_camera;
      const relocalization::RelocalizerOptions& options = relocalizer_.options();
      answer.agrees = difference.translation().norm() <= options.confirm_translation &&
                      Eigen::AngleAxisd(difference.linear()).angle() <=
                          options.confirm_rotation_deg * M_PI / 180.0;
    }
    if (request.add_edge && answer.agrees.value_or(true) && request.reference_keyframe >= 0 &&
        request.reference_keyframe != found.keyframe_id) {
      map::LoopEdge edge;
      edge.match_id = found.keyframe_id;
      edge.query_id = request.reference_keyframe;
      // The reference keyframe's camera in the found keyframe's frame.
      edge.T_match_query = found.T_keyframe_camera * request.T_reference_camera.inverse();
      edge.information = geometry::DiagonalPoseInformation(
          relocalizer_.options().translation_sigma, relocalizer_.options().rotation_sigma_deg);
      edge.inliers = found.inliers;
      edge.probability = found.probability;
      answer.edge = edge;
    }
  }
  answer.ms = clock_() - start + request.describe_ms;
  return answer;
}

map::SavedMap PlaceStage::Save(const MapState& map, const geometry::StereoCamera& camera) const {
  map::SavedMap saved;
  saved.vocabulary_fingerprint = detector_.vocabulary_fingerprint();
  saved.camera = camera;
  const map::KeyframeDatabase& database = detector_.database();
  for (const auto& [id, stored] : database.keyframes()) {
    // A keyframe the map's last word does not hold yet is placed by its odometry and map -> odom.
    saved.keyframes.push_back(
        {stored.keyframe, stored.words,
         map.Contains(id) ? map.MapPose(id) : map.MapToOdom() * stored.keyframe.T_world_camera});
  }
  for (const backend::PoseGraphEdge& edge : map.LoopEdges()) {
    if (!database.Contains(edge.from) || !database.Contains(edge.to)) continue;
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

void PlaceStage::CheckFits(const map::SavedMap& saved, const geometry::StereoCamera& camera) const {
  if (saved.vocabulary_fingerprint != detector_.vocabulary_fingerprint()) {
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

LoadedMap PlaceStage::Load(const map::SavedMap& saved, const geometry::StereoCamera& camera) {
  CheckFits(saved, camera);
  MappingStage::CheckGraph(saved);  // the mapping stage loads the same map's graph after this
  // Built aside and swapped in, so that a failure leaves the running map as it was.
  place_recognition::LoopDetector restored = detector_.WithoutKeyframes();
  LoadedMap loaded;
  try {
    for (const map::SavedKeyframe& keyframe : saved.keyframes) {
      restored.Add(keyframe.keyframe, keyframe.words);
      loaded.next_keyframe_id = std::max(loaded.next_keyframe_id, keyframe.keyframe.id + 1);
      for (const std::int64_t point : keyframe.keyframe.map_point_ids) {
        loaded.next_point_id = std::max(loaded.next_point_id, point + 1);
      }
    }
  } catch (const std::invalid_argument& error) {
    throw io::InputError(std::string("the map is inconsistent: ") + error.what());
  }
  detector_ = std::move(restored);
  loaded.keyframes = saved.keyframes.size();
  return loaded;
}

}  // namespace stereo_fabmap_slam::pipeline
