#pragma once

#include <cstdint>
#include <functional>
#include <optional>
#include <string>

#include <Eigen/Geometry>
#include <opencv2/core.hpp>

#include "stereo_fabmap_slam/features/stereo_features.h"
#include "stereo_fabmap_slam/geometry/stereo_camera.h"
#include "stereo_fabmap_slam/map/keyframe.h"
#include "stereo_fabmap_slam/map/loop_edge.h"
#include "stereo_fabmap_slam/map/map_file.h"
#include "stereo_fabmap_slam/pipeline/map_state.h"
#include "stereo_fabmap_slam/pipeline/mapping_stage.h"
#include "stereo_fabmap_slam/place_recognition/loop_detector.h"
#include "stereo_fabmap_slam/place_recognition/place_recognition_options.h"
#include "stereo_fabmap_slam/relocalization/relocalizer.h"

namespace stereo_fabmap_slam::pipeline {

// A keyframe's loop detection: FAB-MAP's candidates, their verification, the loop if any.
struct PlaceResult {
  std::int64_t keyframe_id = -1;
  double timestamp = 0;  // [s] of the keyframe's image
  place_recognition::LoopDetection detection;
  double detection_ms = 0;  // FAB-MAP and verification
};

// One frame to find in the map (the tracking stage asks, the place stage answers).
struct RelocalizationRequest {
  // kMap: only keyframes in the map (the frame's own segment is cut off by a loss, and a
  // relocalization edge is to join it); kAnywhere: every keyframe (a check of the view, and
  // localization mode).
  enum class Scope { kMap, kAnywhere };
  double timestamp = 0;
  features::StereoFeatures features;  // the frame's, as the odometry extracted them
  cv::Mat place_descriptors;
  Scope scope = Scope::kAnywhere;
  // The keyframe the odometry tracks the frame against (-1: none), and the frame's camera in
  // it: on success the relocalization edge joins that keyframe to the keyframe found.
  std::int64_t reference_keyframe = -1;
  Eigen::Isometry3d T_reference_camera = Eigen::Isometry3d::Identity();
  Eigen::Isometry3d T_odom_camera = Eigen::Isometry3d::Identity();  // the tracked pose
  bool add_edge = false;  // on success, make the relocalization edge (mapping stage)
  // A candidate to confirm (mapping, after a loss): where an earlier relocalization's
  // map -> odom puts this frame's camera. The edge is made only if the relocalization agrees
  // with it (RelocalizerOptions::confirm_translation, confirm_rotation_deg).
  std::optional<Eigen::Isometry3d> expected_T_map_camera;
  bool from_user = false;  // the relocalize service's request, not the recovery's
  double describe_ms = 0;  // place descriptors made for the request
};

struct RelocalizationAnswer {
  relocalization::Relocalization result;
  // kMap: the frame's segment is in the map already (a loop joined it); nothing was tried.
  bool already_joined = false;
  // Whether the map held the found keyframe's map pose; T_map_camera is the frame's camera in
  // map then (the keyframe's map pose times the relocalized relative pose).
  bool map_pose_known = false;
  Eigen::Isometry3d T_map_camera = Eigen::Isometry3d::Identity();
  std::optional<map::LoopEdge> edge;  // for the mapping stage, when add_edge and found
  // With an expected pose and success: whether the found pose agrees with it (no edge if not).
  std::optional<bool> agrees;
  double ms = 0;  // candidates, verification (and the request's describing)
};

// What a loaded map means to the other stages.
struct LoadedMap {
  std::size_t keyframes = 0;
  std::int64_t next_keyframe_id = 0;  // new keyframes and points are numbered from here
  std::int64_t next_point_id = 0;
};

class PlaceStage;

// A question for loop detection from outside the pipeline (the detect_loop service): about a
// keyframe of the map (`stored_id` >= 0), or about `keyframe`, which joins the map first if `add`.
struct LoopQuery {
  std::int64_t stored_id = -1;
  map::Keyframe keyframe;
  bool add = false;
};

// Why `stage` cannot answer `query` (empty: it can): a stored keyframe it does not hold, a
// keyframe without place descriptors or image features, one to add that it holds already.
// `stage` null: none is made yet (no keyframe, camera or map so far), so it holds nothing.
std::string LoopQueryRefusal(const LoopQuery& query, const PlaceStage* stage);

// The place stage (the LoopDetector nodelet; run in order by StereoSlam): the keyframe
// database, FAB-MAP, loop detection with geometric verification, relocalization, and the map's
// files. It keeps every keyframe the mapping stage took into its graph; where the map's pieces
// lie and the keyframes' map poses come from the mapping stage (MapState). The clock
// (milliseconds) is only read to fill the timings.
class PlaceStage {
 public:
  using Clock = std::function<double()>;

  PlaceStage(place_recognition::LoopDetector detector,
             const relocalization::RelocalizerOptions& relocalizer_options, Clock clock);

  // The vocabulary, Chow-Liu tree and (for the sampling model) training places of
  // options.vocabulary_directory; throws io::InputError for missing or damaged files.
  static place_recognition::LoopDetector LoadDetector(
      const place_recognition::PlaceRecognitionOptions& options,
      const place_recognition::LoopDetectorOptions& detector_options,
      const geometry::StereoCamera& camera, int descriptor_norm, double max_descriptor_distance);

  // A keyframe the mapping stage mapped (`mapped`): the update's poses refresh the stored
  // keyframes, and if the graph took the keyframe it becomes a place, at its adjusted pose and
  // in the segment the graph gave it. Throws std::invalid_argument for a keyframe whose place
  // descriptors do not fit the vocabulary.
  void AddKeyframe(const map::Keyframe& keyframe, const MappedKeyframe& mapped);
  // Loop detection of a keyframe added before (std::out_of_range for another).
  PlaceResult DetectLoop(std::int64_t keyframe_id);
  // Loop detection as a LoopQuery asks it (a keyframe added first is a place like the mapping
  // stage's). Throws std::invalid_argument with LoopQueryRefusal's reason for a query it cannot
  // answer.
  place_recognition::LoopDetection Answer(const LoopQuery& query);

  // Finds a frame in the map. Throws std::invalid_argument for place descriptors that do not fit
  // the vocabulary.
  RelocalizationAnswer Relocalize(const RelocalizationRequest& request, const MapState& map) const;

  // The map as a file holds it; `camera` is the rig it was made with.
  map::SavedMap Save(const MapState& map, const geometry::StereoCamera& camera) const;
  // Replaces the keyframes and places by a saved map's after checking that it was made with this
  // vocabulary and `camera` and that its graph can be rebuilt (MappingStage::CheckGraph); throws
  // io::InputError saying why not, leaving the stage as it was.
  // The mapping stage loads the same map's graph (MappingStage::Load), the tracking stage
  // numbers its keyframes and points from the returned ids.
  LoadedMap Load(const map::SavedMap& saved, const geometry::StereoCamera& camera);
  // Throws io::InputError when `saved` was made with another vocabulary or camera.
  void CheckFits(const map::SavedMap& saved, const geometry::StereoCamera& camera) const;

  bool empty() const { return detector_.database().empty(); }
  const place_recognition::LoopDetector& detector() const { return detector_; }
  const relocalization::RelocalizerOptions& relocalizer_options() const {
    return relocalizer_.options();
  }

 private:
  place_recognition::LoopDetector detector_;
  relocalization::Relocalizer relocalizer_;
  Clock clock_;
};

}  // namespace stereo_fabmap_slam::pipeline
