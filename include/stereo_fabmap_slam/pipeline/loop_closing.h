#pragma once

#include <functional>

#include "stereo_fabmap_slam/backend/pose_graph.h"
#include "stereo_fabmap_slam/map/keyframe.h"
#include "stereo_fabmap_slam/map/keyframe_update.h"
#include "stereo_fabmap_slam/map/map_file.h"
#include "stereo_fabmap_slam/place_recognition/loop_detector.h"
#include "stereo_fabmap_slam/place_recognition/place_recognition_options.h"

namespace stereo_fabmap_slam::pipeline {

struct LoopClosingOutput {
  place_recognition::LoopDetection detection;
  bool optimised = false;
  double detection_ms = 0;   // FAB-MAP and verification
  double pose_graph_ms = 0;  // optimisation after an accepted loop
};

// The loop-closing stage: each keyframe (after its bundle adjustment) becomes a place; a
// verified revisit becomes a loop edge of the pose graph, which is then optimised. Keyframe
// poses in `map` and the map -> odom correction come from here; odometry stays as it was.
class LoopClosing {
 public:
  using Clock = std::function<double()>;  // milliseconds, only read to fill the timings

  LoopClosing(place_recognition::LoopDetector detector,
              const backend::PoseGraphOptions& pose_graph_options, Clock clock);

  // Loads the vocabulary, Chow-Liu tree and (for the sampling model) training places of
  // options.vocabulary_directory; throws io::InputError for missing or damaged files.
  static place_recognition::LoopDetector LoadDetector(
      const place_recognition::PlaceRecognitionOptions& options,
      const place_recognition::LoopDetectorOptions& detector_options,
      const geometry::StereoCamera& camera, int descriptor_norm, double max_descriptor_distance);

  // `update` is what the bundle adjustment changed when it added `keyframe` (odom frame): the
  // keyframe joins the map (pose graph, keyframe database, FAB-MAP). DetectLoop then compares it
  // with the map; a caller relocalizes in between (StereoSlam).
  void AddKeyframe(const map::Keyframe& keyframe, const map::KeyframeUpdate& update);
  LoopClosingOutput DetectLoop(std::int64_t keyframe_id);
  // A frame whose reference keyframe is `keyframe_id` was relocalized against `edge.match_id`:
  // the edge (T_match_query = match camera to that keyframe) joins the keyframe's segment to the
  // match's, and the pose graph is optimised. Returns the optimisation's milliseconds.
  double AddRelocalization(const map::LoopEdge& edge);

  // The map as a file needs it (map/map_file.h); `camera` is the rig it was made with.
  map::SavedMap Save(const geometry::StereoCamera& camera) const;
  // Replaces the map with a saved one after checking that it was made with this vocabulary and
  // `camera`; throws io::InputError saying why not, leaving the running map untouched. The next
  // keyframe added starts a new piece of odometry (the saved map's odom is another run's).
  void Load(const map::SavedMap& saved, const geometry::StereoCamera& camera);

  // The parts of Load, for the nodelets that keep them apart (LoopDetector, Backend). Each
  // throws io::InputError for a map that does not fit or is inconsistent.
  static void CheckFits(const map::SavedMap& saved, const place_recognition::LoopDetector& detector,
                        const geometry::StereoCamera& camera);
  static place_recognition::LoopDetector RestoreDetector(
      const map::SavedMap& saved, const place_recognition::LoopDetector& detector);
  static backend::PoseGraph RestorePoseGraph(const map::SavedMap& saved,
                                             const backend::PoseGraphOptions& options);

  const backend::PoseGraph& pose_graph() const { return pose_graph_; }
  const place_recognition::LoopDetector& detector() const { return detector_; }
  bool empty() const { return pose_graph_.size() == 0; }

 private:
  place_recognition::LoopDetector detector_;
  backend::PoseGraphOptions pose_graph_options_;
  backend::PoseGraph pose_graph_;
  Clock clock_;
  bool next_starts_new_map_ = false;  // after Load
  // Keyframes below this id are a loaded map's: the bundle adjustment of this run never moves
  // them (an update with such an id is about this run's keyframes from before the load).
  std::int64_t loaded_below_ = 0;
};

}  // namespace stereo_fabmap_slam::pipeline
