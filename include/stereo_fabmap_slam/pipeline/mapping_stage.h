#pragma once

#include <cstdint>
#include <deque>
#include <functional>
#include <map>
#include <optional>
#include <string>
#include <utility>
#include <variant>
#include <vector>

#include <Eigen/Geometry>

#include "stereo_fabmap_slam/backend/backend_options.h"
#include "stereo_fabmap_slam/backend/global_refinement.h"
#include "stereo_fabmap_slam/backend/local_bundle_adjuster.h"
#include "stereo_fabmap_slam/backend/pose_graph.h"
#include "stereo_fabmap_slam/geometry/stereo_camera.h"
#include "stereo_fabmap_slam/map/keyframe.h"
#include "stereo_fabmap_slam/map/keyframe_update.h"
#include "stereo_fabmap_slam/map/loop_edge.h"
#include "stereo_fabmap_slam/map/map_file.h"
#include "stereo_fabmap_slam/pipeline/map_state.h"
#include "stereo_fabmap_slam/pipeline/slam_mode.h"

namespace stereo_fabmap_slam::pipeline {

// What the mapping stage made of one keyframe: the tracker's and the place stage's input.
struct MappedKeyframe {
  std::int64_t keyframe_id = -1;
  double timestamp = 0;  // [s] of the keyframe's image
  // What the bundle adjustment changed (odom frame): the tracker's local map follows it; the
  // place stage's stored keyframes too. Empty when the keyframe only joined the window.
  map::KeyframeUpdate update;
  // The keyframe joined the pose graph (mapping mode, not a keyframe from before a loaded map):
  // the place stage makes it a place. In localization mode the map is not extended.
  bool in_map_graph = false;
  // As the pose graph took it: tracking was lost before it, or it is the first keyframe after a
  // loaded map or after localization mode. Meaningful when in_map_graph.
  bool starts_new_segment = false;
  double bundle_adjustment_ms = 0;
  double pose_graph_ms = 0;  // optimising edges that waited for this keyframe
};

// The mapping stage's inputs as a driver that runs it beside the other stages receives them (the
// Backend nodelet), to be taken in order of arrival by MappingStage::Take.
struct KeyframeInput {
  map::Keyframe keyframe;
  geometry::StereoCamera camera;  // the rig its features were measured with
};
struct LoopDetectionInput {  // the place stage's answer for a keyframe (PlaceResult)
  std::int64_t keyframe_id = -1;
  std::optional<map::LoopEdge> loop;
};
struct RelocalizationEdgeInput {
  map::LoopEdge edge;
};
struct LoadedMapInput {  // a map the place stage loaded and checked
  map::SavedMap saved;
  std::string name;  // for the news: the file's path
};
struct LocalizationCorrectionInput {  // the tracking stage's map -> odom in localization mode
  Eigen::Isometry3d T_map_odom = Eigen::Isometry3d::Identity();
};
using MappingInput = std::variant<KeyframeInput, LoopDetectionInput, RelocalizationEdgeInput,
                                  LoadedMapInput, SlamMode, LocalizationCorrectionInput>;

// What MappingStage::Take made of a batch of inputs.
struct MappingBatchResult {
  // One per keyframe input, with the input's index in the batch, in order.
  std::vector<std::pair<std::size_t, MappedKeyframe>> keyframes;
  bool map_changed = false;  // keyframes, edges or a map joined: the map is worth publishing
  // For the driver's log: warnings (inputs refused, edges refused, a first keyframe that is not
  // the run's first) and news (optimisations, a map loaded).
  std::vector<std::string> warnings;
  // Said when several keyframes waited (empty otherwise): under load it comes with every batch,
  // so a driver may say it at a limited rate.
  std::string falling_behind;
  std::vector<std::string> news;
};

// The mapping stage (the Backend nodelet; run in order by StereoSlam): every keyframe joins the
// windowed bundle adjustment (odom frame), whose update goes back to the tracker, and, in
// mapping mode, the pose graph (map frame); loop and relocalization edges join the graph, which
// is then optimised. It owns the map's connectivity (segments and pieces, MapState), map -> odom,
// the edges that wait for their keyframes, and what a loaded map does to the next keyframe.
// The clock (milliseconds) is only read to fill the timings.
class MappingStage : public MapState {
 public:
  using Clock = std::function<double()>;

  MappingStage(const backend::BundleAdjustmentOptions& bundle_adjustment,
               const backend::PoseGraphOptions& pose_graph, Clock clock);

  // The inputs that waited while the stage worked, in order of arrival. Every keyframe joins the
  // map, but only the newest of the batch's keyframes is followed by a bundle adjustment, whose
  // window covers the others: a driver that fell behind the tracker catches up instead of
  // falling further behind (adjusting each would cost a window's optimisation per keyframe).
  // An input that cannot be taken (a keyframe of another camera, a map whose graph cannot be
  // rebuilt) is skipped and said in the warnings; the others are taken.
  MappingBatchResult Take(const std::vector<MappingInput>& batch);

  // A keyframe of the tracker, taken in order of id. `camera` is the rig its features were
  // measured with (the first keyframe's sets the bundle adjustment's; std::invalid_argument for
  // a keyframe of another). With optimise = false the keyframe joins the window without an
  // optimisation (a caller behind the tracker adjusts the newest of several at once). A keyframe
  // made before a loaded map (an id the map's keyframes may have) is dropped: in_map_graph false
  // and no update.
  MappedKeyframe AddKeyframe(const map::Keyframe& keyframe, const geometry::StereoCamera& camera,
                             bool optimise = true);
  // A verified loop (kLoop) or relocalization (kRelocalization) edge. It joins the graph at once,
  // and the graph is optimised, if the graph holds both keyframes; otherwise it waits for them
  // (the nodelets' place stage can be ahead of the bundle adjustment). Returns the milliseconds
  // of the optimisation (0 if it waits). An edge the graph refuses (a loop of a keyframe with
  // itself, a bad information matrix) is left out and said so by TakeRefusedEdges.
  double AddEdge(const map::LoopEdge& edge, backend::PoseGraphEdgeType type);
  // The place stage's answer for a keyframe: its loop, if any, joins the graph (AddEdge). The
  // keyframe counts as closed either way (last_closed_keyframe: what a driver that runs the
  // stages in lockstep waits for).
  double ApplyLoopDetection(std::int64_t keyframe_id, const std::optional<map::LoopEdge>& loop);

  // Bundle adjustment of the whole map in the map frame (backend::GlobalRefinement): the
  // keyframes joined to the map's first (which stays fixed, as does any keyframe of a loaded map,
  // whose points are not kept), the points the bundle adjustment keeps, moved into the map frame
  // with the keyframe that saw them first, and the graph's edges. The graph adopts the result
  // (PoseGraph::AdoptRefinement). Nothing to do (an empty summary) while the map has no loop or
  // relocalization edge (the windowed bundle adjustment has refined the odometry already), in
  // localization mode (the map stays as it is), or when every keyframe is fixed.
  // global_refinements() counts the refinements that moved keyframes.
  backend::GlobalRefinementSummary RefineGlobally(const backend::GlobalRefinementOptions& options);
  // The refinement's options; with options.after_loop_closing the stage refines the whole map
  // after every optimisation of the whole pose graph (in its time: pose_graph_ms). With
  // after_loop_closing or at_end (a driver's refinement at the end) and fuse_loop_points, the
  // stage keeps the loops' shared points for it; a refinement asked for otherwise fuses none.
  void SetGlobalRefinement(const backend::GlobalRefinementOptions& options);
  std::uint64_t global_refinements() const { return global_refinements_; }

  // Localization mode leaves the graph as it is; map -> odom then follows the tracking stage's
  // relocalizations (SetLocalizationCorrection). Back in mapping mode, the next keyframe starts
  // a new segment: the keyframes of the localization time are not in the graph.
  void SetMode(SlamMode mode);
  SlamMode mode() const { return mode_; }
  void SetLocalizationCorrection(const Eigen::Isometry3d& T_map_odom);

  // Replaces the graph by a saved map's (after the place stage checked the file fits); throws
  // io::InputError for a map whose graph cannot be rebuilt, leaving everything as it was. The
  // bundle adjustment starts afresh (the tracker starts a new local map), keyframes from before
  // the load are dropped, and the next keyframe starts a new segment.
  void Load(const map::SavedMap& saved);
  // Throws io::InputError for a saved map whose graph cannot be rebuilt (what Load would refuse),
  // so that a driver can check a map before any stage changes.
  static void CheckGraph(const map::SavedMap& saved);

  // MapState.
  bool empty() const override { return graph_.size() == 0; }
  bool Contains(std::int64_t id) const override { return graph_.Contains(id); }
  bool InMap(std::int64_t id) const override { return graph_.InMap(id); }
  Eigen::Isometry3d MapPose(std::int64_t id) const override;
  std::map<std::int64_t, Eigen::Isometry3d> MapPoses() const override { return graph_.MapPoses(); }
  Eigen::Isometry3d MapToOdom() const override;
  std::vector<backend::PoseGraphEdge> LoopEdges() const override;
  // The whole state as a copy (what the Backend publishes as map_graph).
  MapSnapshot Snapshot() const;

  const backend::PoseGraph& pose_graph() const { return graph_; }
  // The rig of the keyframes (the first one's, or a loaded map's); none before either.
  const std::optional<geometry::StereoCamera>& camera() const { return camera_; }
  // The newest keyframe whose loop detection was applied, or that has none to wait for (not in
  // the graph); -1 before any.
  std::int64_t last_closed_keyframe() const { return last_closed_keyframe_; }
  // Relocalization edges received (joined or refused), for a driver in lockstep.
  std::uint64_t relocalization_edges_received() const { return relocalization_edges_received_; }
  // Keyframes below this id belong to a loaded map (0 without one).
  std::int64_t loaded_below() const { return loaded_below_; }
  std::size_t waiting_edges() const { return waiting_edges_.size(); }
  // Optimisations of the graph so far, and what the last one did (for the log).
  std::uint64_t optimisations() const { return optimisations_; }
  const backend::PoseGraphSummary& last_optimisation() const { return last_optimisation_; }
  // Why the edges refused since the last call were refused, for the driver to report.
  std::vector<std::string> TakeRefusedEdges();

 private:
  struct WaitingEdge {
    map::LoopEdge edge;
    backend::PoseGraphEdgeType type;
  };
  // Adds the waiting edges whose keyframes the graph now holds, and those it can never hold
  // (keyframes older than the newest that it does not have) are dropped. True if any joined.
  bool AddReadyEdges();
  double Optimise();
  // One input of Take; true if the map changed.
  bool TakeOne(const MappingInput& input, std::size_t index, bool optimise,
               MappingBatchResult* result);

  backend::BundleAdjustmentOptions bundle_adjustment_options_;
  backend::PoseGraphOptions pose_graph_options_;
  Clock clock_;
  std::optional<geometry::StereoCamera> camera_;
  std::optional<backend::LocalBundleAdjuster> bundle_adjuster_;  // made with the first keyframe
  backend::PoseGraph graph_;
  std::deque<WaitingEdge> waiting_edges_;
  std::vector<std::string> refused_edges_;
  SlamMode mode_ = SlamMode::kMapping;
  bool next_starts_new_segment_ = false;  // after a load, and after localization mode
  // The time of the graph's newest keyframe (this run's), for the gap of a tracking loss.
  std::optional<double> last_graph_keyframe_time_;
  std::int64_t loaded_below_ = 0;
  std::optional<Eigen::Isometry3d> localization_correction_;  // localization mode's map -> odom
  std::int64_t last_closed_keyframe_ = -1;
  std::uint64_t relocalization_edges_received_ = 0;
  std::uint64_t optimisations_ = 0;
  backend::PoseGraphSummary last_optimisation_;
  backend::GlobalRefinementOptions global_refinement_options_;
  // The map points the graph's loops verified as one place on two passes (query's, match's),
  // kept when the refinement options ask for a refinement that fuses them.
  std::vector<std::pair<std::int64_t, std::int64_t>> loop_shared_points_;
  std::uint64_t global_refinements_ = 0;
};

}  // namespace stereo_fabmap_slam::pipeline
