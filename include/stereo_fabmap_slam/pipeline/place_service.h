#pragma once

#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "stereo_fabmap_slam/geometry/stereo_camera.h"
#include "stereo_fabmap_slam/map/keyframe.h"
#include "stereo_fabmap_slam/map/map_file.h"
#include "stereo_fabmap_slam/pipeline/map_state.h"
#include "stereo_fabmap_slam/pipeline/mapping_stage.h"
#include "stereo_fabmap_slam/pipeline/place_stage.h"
#include "stereo_fabmap_slam/pipeline/slam_mode.h"

namespace stereo_fabmap_slam::pipeline {

// What a request about a map file came to, in words for whoever asked.
struct MapFileAnswer {
  bool success = false;
  std::size_t keyframes = 0;
  std::string message;
};

// A map file the place stage took: what the other stages are told, and the file's map for a
// mapping stage that runs beside it (StereoSlam's; the Backend reads the file itself).
struct LoadedMapFile {
  std::string path;  // from the root
  LoadedMap loaded;
  map::SavedMap saved;
};

// A mode asked for by name: the mode, or none and why.
struct ModeAnswer {
  std::optional<SlamMode> mode;
  std::string message;
};
ModeAnswer ModeNamed(const std::string& name);

// The place stage with what every driver's user asks of it: map files and modes by path and by
// name, with every refusal said in words, and the map the answers are about. The LoopDetector
// nodelet makes it empty, and its stage once the map's camera is known (the first keyframe's,
// or a loaded map's: the vocabulary's words depend on it), and keeps the map it follows (the
// Backend's map_graph, or a file just loaded) beside it. StereoSlam, which knows its camera from
// the start, makes it with its stage and runs the stage's steps in order itself. One caller at a
// time, but for FollowMap and followed_map.
class PlaceService {
 public:
  // Makes the place stage for a camera (loads the vocabulary; throws io::InputError).
  using StageMaker = std::function<PlaceStage(const geometry::StereoCamera&)>;
  explicit PlaceService(StageMaker make_stage) : make_stage_(std::move(make_stage)) {}
  // A service whose stage is made, for `camera`, beside a mapping stage of its driver's own, whose
  // map it is given with each call: it follows no map (a loaded file's is not rebuilt for it).
  PlaceService(PlaceStage stage, const geometry::StereoCamera& camera);

  // The mode and map file a user asked for at start ("": no file). A mode that is none, or a map
  // that cannot be loaded, leaves the service empty and mapping, with `errors` saying why: the
  // odometry goes on, and LoadMap or a mode given later put it right without a restart.
  struct StartUp {
    SlamMode mode = SlamMode::kMapping;
    std::optional<LoadedMapFile> map;
    std::vector<std::string> errors;
  };
  StartUp Start(const std::string& mode_name, const std::string& map_file);

  // A keyframe and the mapping stage's answer to it: a place if the graph took it, and then its
  // loop detection. `warnings`: the first keyframe of a service started while the odometry ran
  // (the keyframes before it are no places). Throws std::invalid_argument for place descriptors
  // that do not fit the vocabulary.
  struct KeyframeOutcome {
    std::optional<PlaceResult> result;
    std::vector<std::string> warnings;
  };
  KeyframeOutcome Take(const map::Keyframe& keyframe, const geometry::StereoCamera& camera,
                       const MappedKeyframe& mapped);
  // The mapping stage's answer to a keyframe whose own message never arrived (a service started
  // while the tracker ran): no place, and a warning that says so.
  KeyframeOutcome Take(const MappedKeyframe& mapped);

  // Loop detection of a LoopQuery (PlaceStage::Answer); `camera`: the query's keyframe's, for a
  // service that has no stage yet. Throws std::invalid_argument with LoopQueryRefusal's reason.
  place_recognition::LoopDetection Answer(const LoopQuery& query,
                                          const geometry::StereoCamera& camera);
  // PlaceStage::Relocalize; an empty map answers kEmptyMap.
  RelocalizationAnswer Relocalize(const RelocalizationRequest& request, const MapState& map) const;

  // Saves the map (`map`: the mapping stage's state) to `path`; refuses an empty map. Answers
  // name the whole path (a relative one is the working directory's). A failed save leaves no
  // file behind.
  MapFileAnswer SaveMap(const std::string& path, const MapState& map) const;
  // Replaces the map by the file's (PlaceStage::Load's checks), and the followed map by the
  // file's as the mapping stage rebuilds it; on success `loaded` receives what to tell the other
  // stages, its path whole. A refused file leaves the map as it was and says why.
  MapFileAnswer LoadMap(const std::string& path, std::optional<LoadedMapFile>* loaded);

  // The mapping stage's map as a driver that runs apart from it last heard (map_graph), for
  // Relocalize and SaveMap; a loaded file's until the mapping stage says otherwise. Any thread.
  void FollowMap(std::shared_ptr<const MapSnapshot> map) { std::atomic_store(&followed_, map); }
  std::shared_ptr<const MapSnapshot> followed_map() const { return std::atomic_load(&followed_); }

  bool empty() const { return !stage_ || stage_->empty(); }
  const PlaceStage* stage() const { return stage_ ? &*stage_ : nullptr; }
  PlaceStage* stage() { return stage_ ? &*stage_ : nullptr; }

 private:
  PlaceStage& StageFor(const geometry::StereoCamera& camera);
  // LoadMap's work; throws saying why a file is refused (the map is then as it was).
  LoadedMapFile Load(const std::string& path);

  StageMaker make_stage_;
  std::optional<PlaceStage> stage_;
  std::optional<geometry::StereoCamera> camera_;  // the stage's
  std::shared_ptr<const MapSnapshot> followed_ = std::make_shared<MapSnapshot>();
  bool follows_map_ = true;  // false beside the driver's own mapping stage (StereoSlam)
};

}  // namespace stereo_fabmap_slam::pipeline
