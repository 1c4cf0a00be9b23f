#include "stereo_fabmap_slam/pipeline/place_service.h"

#include <filesystem>
#include <stdexcept>

#include "stereo_fabmap_slam/map/map_file.h"

namespace stereo_fabmap_slam::pipeline {
namespace {

// A saved map's state as the mapping stage has it once it has loaded the same map.
MapSnapshot SnapshotOfSavedMap(const map::SavedMap& saved) {
  MappingStage mapping(backend::BundleAdjustmentOptions(), backend::PoseGraphOptions(),
                       [] { return 0.0; });
  mapping.Load(saved);
  return mapping.Snapshot();
}

// `path` from the root: a relative path is the process's working directory's (under roslaunch
// $ROS_HOME, which the caller of a service may not know), so answers name the whole path.
std::string WholePath(const std::string& path) {
  if (path.empty()) throw std::invalid_argument("no file named (an empty path)");
  return std::filesystem::absolute(path).lexically_normal().string();
}

}  // namespace

ModeAnswer ModeNamed(const std::string& name) {
  ModeAnswer answer;
  answer.mode = ParseSlamMode(name);
  answer.message =
      answer.mode ? "mode " + name : "unknown mode '" + name + "' (mapping, localization)";
  return answer;
}

PlaceService::PlaceService(PlaceStage stage, const geometry::StereoCamera& camera)
    : make_stage_([](const geometry::StereoCamera&) -> PlaceStage {
        throw std::logic_error("PlaceService: its stage was made with it");
      }),
      stage_(std::move(stage)),
      camera_(camera),
      follows_map_(false) {}

PlaceService::StartUp PlaceService::Start(const std::string& mode_name,
                                          const std::string& map_file) {
  StartUp start;
  if (const std::optional<SlamMode> mode = ParseSlamMode(mode_name)) {
    start.mode = *mode;
  } else {
    start.errors.push_back("~mode '" + mode_name +
                           "' is not a mode (mapping, localization): mapping");
  }
  if (map_file.empty()) return start;
  try {
    start.map = Load(map_file);
  } catch (const std::exception& error) {
    // Localization needs a map: without the one asked for, the odometry maps afresh.
    start.mode = SlamMode::kMapping;
    start.errors.push_back(std::string("~map_file refused: ") + error.what() +
                           "; running with an empty map in mapping mode");
  }
  return start;
}

PlaceStage& PlaceService::StageFor(const geometry::StereoCamera& camera) {
  if (!stage_) {
    stage_.emplace(make_stage_(camera));
    camera_ = camera;
  }
  return *stage_;
}

PlaceService::KeyframeOutcome PlaceService::Take(const map::Keyframe& keyframe,
                                                 const geometry::StereoCamera& camera,
                                                 const MappedKeyframe& mapped) {
  KeyframeOutcome outcome;
  // Started (or restarted) while the odometry ran: say what its places do not cover.
  if (!stage_ && keyframe.id > 0) {
    outcome.warnings.push_back(
        "first keyframe received is " + std::to_string(keyframe.id) +
        ": the keyframes before it are not places of this LoopDetector (restarted while the "
        "tracker ran?)");
  }
  PlaceStage& stage = StageFor(camera);
  stage.AddKeyframe(keyframe, mapped);
  if (mapped.in_map_graph) outcome.result = stage.DetectLoop(mapped.keyframe_id);
  return outcome;
}

PlaceService::KeyframeOutcome PlaceService::Take(const MappedKeyframe& mapped) {
  KeyframeOutcome outcome;
  outcome.warnings.push_back("keyframe " + std::to_string(mapped.keyframe_id) +
                             " joined the map, but its keyframe message never arrived (restarted "
                             "while the tracker ran?): it is no place");
  return outcome;
}

place_recognition::LoopDetection PlaceService::Answer(const LoopQuery& query,
                                                      const geometry::StereoCamera& camera) {
  // A stored keyframe needs a stage that holds it; only a keyframe to compare makes one.
  const std::string refusal = LoopQueryRefusal(query, stage());
  if (!refusal.empty()) throw std::invalid_argument(refusal);
  return (query.stored_id >= 0 ? *stage_ : StageFor(camera)).Answer(query);
}

RelocalizationAnswer PlaceService::Relocalize(const RelocalizationRequest& request,
                                              const MapState& map) const {
  if (empty()) {
    RelocalizationAnswer answer;
    answer.result.status = relocalization::RelocalizationStatus::kEmptyMap;
    answer.result.reason = "the map is empty";
    return answer;
  }
  return stage_->Relocalize(request, map);
}

MapFileAnswer PlaceService::SaveMap(const std::string& path, const MapState& map) const {
  MapFileAnswer answer;
  if (empty()) {
    answer.message = "the map is empty";
    return answer;
  }
  try {
    const std::string file = WholePath(path);
    const map::SavedMap saved = stage_->Save(map, *camera_);
    map::SaveMapFile(file, saved);
    answer.success = true;
    answer.keyframes = saved.keyframes.size();
    answer.message = "saved " + std::to_string(saved.keyframes.size()) + " keyframes and " +
                     std::to_string(saved.edges.size()) + " loop and relocalization edges to " +
                     file;
  } catch (const std::exception& error) {
    answer.message = error.what();
  }
  return answer;
}

MapFileAnswer PlaceService::LoadMap(const std::string& path, std::optional<LoadedMapFile>* loaded) {
  MapFileAnswer answer;
  try {
    *loaded = Load(path);
    answer.success = true;
    answer.keyframes = (*loaded)->loaded.keyframes;
    answer.message =
        "loaded " + std::to_string(answer.keyframes) + " keyframes from " + (*loaded)->path;
  } catch (const std::exception& error) {
    answer.message = std::string(error.what()) + "; the map is unchanged";
  }
  return answer;
}

LoadedMapFile PlaceService::Load(const std::string& path) {
  const bool fresh = !stage_;
  try {
    const std::string file = WholePath(path);
    const map::SavedMap saved = map::LoadMapFile(file);
    // A service without a stage takes the map's camera; the mapping stage then refuses
    // keyframes of another.
    const LoadedMap loaded = StageFor(saved.camera).Load(saved, *camera_);
    if (follows_map_) FollowMap(std::make_shared<MapSnapshot>(SnapshotOfSavedMap(saved)));
    return {file, loaded, saved};
  } catch (...) {
    if (fresh) {  // no stage made for a map refused: the next keyframe brings the camera
      stage_.reset();
      camera_.reset();
    }
    throw;
  }
}

}  // namespace stereo_fabmap_slam::pipeline
