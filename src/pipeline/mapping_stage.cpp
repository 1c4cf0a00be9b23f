#include "stereo_fabmap_slam/pipeline/mapping_stage.h"

#include <algorithm>
#include <cmath>
#include <functional>
#include <stdexcept>
#include <string>
#include <unordered_map>

#include "stereo_fabmap_slam/io/input_error.h"

namespace stereo_fabmap_slam::pipeline {
namespace {

bool SameCamera(const geometry::StereoCamera& a, const geometry::StereoCamera& b) {
  const auto near = [](double x, double y) { return std::abs(x - y) <= 1e-6 * std::abs(y); };
  return a.size == b.size && near(a.fx, b.fx) && near(a.fy, b.fy) && near(a.cx, b.cx) &&
         near(a.cy, b.cy) && near(a.baseline, b.baseline);
}

// The pose graph of a saved map: its keyframes (odometry poses and segments), its loop and
// relocalization edges, and its optimised map poses.
backend::PoseGraph RestorePoseGraph(const map::SavedMap& saved,
                                    const backend::PoseGraphOptions& options) {
  backend::PoseGraph graph(options);
  try {
    for (const map::SavedKeyframe& keyframe : saved.keyframes) {
      graph.AddKeyframe(keyframe.keyframe.id, keyframe.keyframe.T_world_camera,
                        keyframe.keyframe.starts_new_segment);
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

}  // namespace

MappingStage::MappingStage(const backend::BundleAdjustmentOptions& bundle_adjustment,
                           const backend::PoseGraphOptions& pose_graph, Clock clock)
    : bundle_adjustment_options_(bundle_adjustment),
      pose_graph_options_(pose_graph),
      clock_(std::move(clock)),
      graph_(pose_graph) {
  // A pose graph that weighs its odometry edges by the steps' covariances needs the bundle
  // adjustment to estimate them.
  if (pose_graph.odometry_covariance_scale > 0) bundle_adjustment_options_.step_covariances = true;
}

MappingBatchResult MappingStage::Take(const std::vector<MappingInput>& batch) {
  MappingBatchResult result;
  std::size_t keyframes = 0;
  for (const MappingInput& input : batch) {
    keyframes += std::holds_alternative<KeyframeInput>(input) ? 1 : 0;
  }
  if (keyframes > 1) {
    result.falling_behind = "bundle adjustment falls behind: " + std::to_string(keyframes) +
                            " keyframes added in one optimisation";
  }
  const std::uint64_t optimisations = optimisations_;
  std::size_t seen = 0;
  for (std::size_t index = 0; index < batch.size(); ++index) {
    const bool keyframe = std::holds_alternative<KeyframeInput>(batch[index]);
    seen += keyframe ? 1 : 0;
    try {
      result.map_changed |= TakeOne(batch[index], index, !keyframe || seen == keyframes, &result);
    } catch (const std::exception& error) {  // std::invalid_argument, io::InputError
      result.warnings.push_back(std::string("input skipped: ") + error.what());
    }
  }
  for (std::string& refused : TakeRefusedEdges()) result.warnings.push_back(std::move(refused));
  if (optimisations_ > optimisations) {
    result.news.push_back(
        "pose graph: " + std::to_string(last_optimisation_.moved_keyframes) + " of " +
        std::to_string(graph_.size()) + " keyframes optimised (" +
        (last_optimisation_.local ? "near loops that agree with the map" : "whole graph") +
        ") in " + std::to_string(last_optimisation_.iterations) + " iterations");
  }
  return result;
}

bool MappingStage::TakeOne(const MappingInput& input, std::size_t index, bool optimise,
                           MappingBatchResult* result) {
  if (const auto* keyframe = std::get_if<KeyframeInput>(&input)) {
    // A mapping stage started while the tracking ran (a Backend restarted): say what its map
    // does not have.
    if (!camera_ && empty() && keyframe->keyframe.id > 0 && loaded_below_ == 0) {
      result->warnings.push_back(
          "first keyframe received is " + std::to_string(keyframe->keyframe.id) +
          ": the keyframes before it are not in this map (the mapping stage started while the "
          "tracking ran?); optimising from here, map -> odom starts at identity");
    }
    result->keyframes.emplace_back(index,
                                   AddKeyframe(keyframe->keyframe, keyframe->camera, optimise));
    return true;
  }
  if (const auto* detection = std::get_if<LoopDetectionInput>(&input)) {
    ApplyLoopDetection(detection->keyframe_id, detection->loop);
    return true;
  }
  if (const auto* edge = std::get_if<RelocalizationEdgeInput>(&input)) {
    AddEdge(edge->edge, backend::PoseGraphEdgeType::kRelocalization);
    return true;
  }
  if (const auto* loaded = std::get_if<LoadedMapInput>(&input)) {
    try {
      Load(loaded->saved);
    } catch (const io::InputError& error) {
      throw io::InputError("map " + loaded->name +
                           " not loaded into the pose graph: " + error.what());
    }
    result->news.push_back("pose graph of " + loaded->name + ": " + std::to_string(graph_.size()) +
                           " keyframes");
    return true;
  }
  if (const auto* mode = std::get_if<SlamMode>(&input)) {
    SetMode(*mode);
    return false;
  }
  SetLocalizationCorrection(std::get<LocalizationCorrectionInput>(input).T_map_odom);
  return false;
}

MappedKeyframe MappingStage::AddKeyframe(const map::Keyframe& keyframe,
                                         const geometry::StereoCamera& camera, bool optimise) {
  MappedKeyframe mapped;
  mapped.keyframe_id = keyframe.id;
  mapped.timestamp = keyframe.timestamp;
  // Made before a loaded map replaced this run's: its id may be one of the map's, and its points
  // are of a local map the tracker has cleared.
  if (keyframe.id < loaded_below_) {
    last_closed_keyframe_ = std::max(last_closed_keyframe_, keyframe.id);
    return mapped;
  }
  if (camera_ && !SameCamera(camera, *camera_)) {
    throw std::invalid_argument("keyframe " + std::to_string(keyframe.id) +
                                " was measured with another camera than the map's");
  }
  if (!bundle_adjuster_) {
    camera_ = camera;
    bundle_adjuster_.emplace(bundle_adjustment_options_, camera);
  }
  double start = clock_();
  mapped.update = bundle_adjuster_->AddKeyframe(keyframe, optimise);
  mapped.bundle_adjustment_ms = clock_() - start;
  if (mode_ != SlamMode::kMapping || keyframe.id <= graph_.last_id()) {
    // Not in the graph: no place, so no loop detection to wait for.
    last_closed_keyframe_ = std::max(last_closed_keyframe_, keyframe.id);
    return mapped;
  }

  // The window's corrections of older keyframes first, then the keyframe at its adjusted pose,
  // so that its map pose continues from its predecessor's corrected one.
  Eigen::Isometry3d T_odom_camera = keyframe.T_world_camera;
  for (const auto& [id, pose] : mapped.update.keyframe_poses) {
    if (id == keyframe.id) {
      T_odom_camera = pose;
    } else if (graph_.Contains(id)) {
      graph_.UpdateOdometryPose(id, pose);
    }
  }
  // A tracking loss that the odometry bridged by its motion model; not a loaded map or the end
  // of localization mode, after which the odometry has nothing to do with the keyframe before.
  const bool after_loss = keyframe.starts_new_segment && !next_starts_new_segment_;
  mapped.starts_new_segment = keyframe.starts_new_segment || next_starts_new_segment_;
  next_starts_new_segment_ = false;
  graph_.AddKeyframe(keyframe.id, T_odom_camera, mapped.starts_new_segment);
  for (const map::KeyframeUpdate::StepCovariance& step : mapped.update.step_covariances) {
    graph_.UpdateOdometryCovariance(step.from, step.to, step.covariance);
  }
  if (after_loss && last_graph_keyframe_time_) {
    graph_.AddGap(keyframe.id, keyframe.timestamp - *last_graph_keyframe_time_);
  }
  last_graph_keyframe_time_ = keyframe.timestamp;
  mapped.in_map_graph = true;
  start = clock_();
  if (AddReadyEdges()) {
    Optimise();
    mapped.pose_graph_ms = clock_() - start;
  }
  return mapped;
}

double MappingStage::AddEdge(const map::LoopEdge& edge, backend::PoseGraphEdgeType type) {
  if (type == backend::PoseGraphEdgeType::kRelocalization) ++relocalization_edges_received_;
  waiting_edges_.push_back({edge, type});
  const double start = clock_();
  if (!AddReadyEdges()) return 0;
  Optimise();
  return clock_() - start;
}

double MappingStage::ApplyLoopDetection(std::int64_t keyframe_id,
                                        const std::optional<map::LoopEdge>& loop) {
  last_closed_keyframe_ = std::max(last_closed_keyframe_, keyframe_id);
  return loop ? AddEdge(*loop, backend::PoseGraphEdgeType::kLoop) : 0.0;
}

bool MappingStage::AddReadyEdges() {
  bool added = false;
  for (auto it = waiting_edges_.begin(); it != waiting_edges_.end();) {
    const std::int64_t a = it->edge.query_id, b = it->edge.match_id;
    const bool ready = graph_.Contains(a) && graph_.Contains(b);
    // Keyframes arrive in order of id: one older than the newest that the graph lacks was
    // dropped (made before a load, or in localization mode) and never comes.
    const bool never = (!graph_.Contains(a) && a <= graph_.last_id()) ||
                       (!graph_.Contains(b) && b <= graph_.last_id());
    if (!ready && !never) {
      ++it;
      continue;
    }
    const WaitingEdge edge = *it;
    it = waiting_edges_.erase(it);
    if (!ready) continue;
    try {
      graph_.AddLoop(edge.edge, edge.type);
      added = true;
      // Kept only for a refinement that will fuse them (16 bytes a pair, ~100 pairs a loop).
      const backend::GlobalRefinementOptions& refinement = global_refinement_options_;
      if (refinement.fuse_loop_points && (refinement.after_loop_closing || refinement.at_end)) {
        loop_shared_points_.insert(loop_shared_points_.end(), edge.edge.shared_points.begin(),
                                   edge.edge.shared_points.end());
      }
    } catch (const std::invalid_argument& error) {
      refused_edges_.push_back("edge " + std::to_string(edge.edge.query_id) + " -> " +
                               std::to_string(edge.edge.match_id) + " refused: " + error.what());
    }
  }
  return added;
}

std::vector<std::string> MappingStage::TakeRefusedEdges() {
  std::vector<std::string> refused;
  refused.swap(refused_edges_);
  return refused;
}

double MappingStage::Optimise() {
  const double start = clock_();
  last_optimisation_ = graph_.Optimize();
  ++optimisations_;
  if (global_refinement_options_.after_loop_closing && !last_optimisation_.local &&
      last_optimisation_.iterations > 0) {
    RefineGlobally(global_refinement_options_);
  }
  return clock_() - start;
}

void MappingStage::SetGlobalRefinement(const backend::GlobalRefinementOptions& options) {
  options.Validate();
  global_refinement_options_ = options;
}

void MappingStage::SetMode(SlamMode mode) {
  if (mode_ == SlamMode::kLocalization && mode == SlamMode::kMapping) {
    next_starts_new_segment_ = true;
    localization_correction_.reset();
  }
  mode_ = mode;
}

backend::GlobalRefinementSummary MappingStage::RefineGlobally(
    const backend::GlobalRefinementOptions& options) {
  // Without a loop there is nothing the windowed bundle adjustment has not refined already; in
  // localization mode the map stays as it is.
  if (!bundle_adjuster_ || !camera_ || LoopEdges().empty() || mode_ == SlamMode::kLocalization) {
    return {};
  }
  backend::GlobalRefinement refinement(options, pose_graph_options_, *camera_,
                                       bundle_adjustment_options_.sigma);
  const std::map<std::int64_t, Eigen::Isometry3d> odometry = bundle_adjuster_->KeyframePoses();
  const std::map<std::int64_t, Eigen::Isometry3d> map_poses = graph_.MapPoses();
  // Per keyframe of the problem: T_map_odom, which carries a point it saw first into the map.
  std::map<std::int64_t, Eigen::Isometry3d> corrections;
  const std::int64_t anchor = map_poses.begin()->first;
  for (const auto& [id, pose] : map_poses) {
    if (!graph_.InMap(id)) continue;
    const auto odometry_pose = odometry.find(id);
    const bool has_points = odometry_pose != odometry.end();
    refinement.AddKeyframe(id, pose, id == anchor || !has_points);
    if (has_points) corrections[id] = pose * odometry_pose->second.inverse();
  }
  // The map points verified as one place on two passes (loops' shared points) are one point:
  // each group of them (union-find over the pairs) takes all their observations.
  std::unordered_map<std::int64_t, std::int64_t> parent;
  const std::function<std::int64_t(std::int64_t)> root = [&](std::int64_t id) {
    auto it = parent.find(id);
    if (it == parent.end() || it->second == id) return id;
    const std::int64_t top = root(it->second);
    it->second = top;
    return top;
  };
  if (options.fuse_loop_points) {
    // Where each point is in the map (by its first observer in the problem): a pair whose two
    // points lie further apart than the refinement allows is a wrong match, not fused.
    std::unordered_map<std::int64_t, Eigen::Vector3d> position;
    bundle_adjuster_->ForEachPoint([&](std::int64_t id, const Eigen::Vector3d& point_odom,
                                       const std::vector<backend::PointObservation>& observations) {
      for (const backend::PointObservation& o : observations) {
        const auto correction = corrections.find(o.keyframe);
        if (correction == corrections.end()) continue;
        position.emplace(id, correction->second * point_odom);
        return;
      }
    });
    for (const auto& [a, b] : loop_shared_points_) {
      const auto position_a = position.find(a), position_b = position.find(b);
      if (position_a == position.end() || position_b == position.end() ||
          (position_a->second - position_b->second).norm() > options.fuse_max_distance) {
        continue;
      }
      parent.try_emplace(a, a);
      parent.try_emplace(b, b);
      const std::int64_t root_a = root(a), root_b = root(b);
      // Pairs within reach can still chain look-alikes into one group across a corridor: two
      // groups join only if their roots are within reach too, so that every point of a group
      // lies within fuse_max_distance of its root.
      if (root_a == root_b ||
          (position.at(root_a) - position.at(root_b)).norm() > options.fuse_max_distance) {
        continue;
      }
      parent[std::max(root_a, root_b)] = std::min(root_a, root_b);
    }
  }
  struct FusedPoint {
    std::optional<Eigen::Vector3d> position;  // map frame, by its first observer in the problem
    std::vector<backend::PointObservation> observations;
  };
  std::map<std::int64_t, FusedPoint> fused;  // by the group's root id
  bundle_adjuster_->ForEachPoint([&](std::int64_t id, const Eigen::Vector3d& point_odom,
                                     const std::vector<backend::PointObservation>& observations) {
    const bool in_group = parent.count(id) > 0;
    if (observations.size() < 2 && !in_group) return;
    FusedPoint& point = fused[in_group ? root(id) : id];
    for (const backend::PointObservation& o : observations) {
      const auto correction = corrections.find(o.keyframe);
      if (correction == corrections.end()) continue;
      if (!point.position) point.position = correction->second * point_odom;
      // A keyframe sees a place once: a second key point of it in the same group is dropped.
      const bool seen = std::any_of(
          point.observations.begin(), point.observations.end(),
          [&](const backend::PointObservation& other) { return other.keyframe == o.keyframe; });
      if (!seen) point.observations.push_back(o);
    }
  });
  for (const auto& [id, point] : fused) {
    if (point.position) refinement.AddPoint(*point.position, point.observations);
  }
  for (const backend::PoseGraphEdge& edge : graph_.Edges()) refinement.AddEdge(edge);
  const backend::GlobalRefinementSummary summary = refinement.Solve();
  // Every keyframe fixed (a loaded map with nothing new): nothing moved, no steps to adopt.
  if (summary.keyframes == 0) return summary;
  ++global_refinements_;
  graph_.AdoptRefinement(refinement.Poses());
  return summary;
}

void MappingStage::SetLocalizationCorrection(const Eigen::Isometry3d& T_map_odom) {
  if (mode_ == SlamMode::kLocalization) localization_correction_ = T_map_odom;
}

void MappingStage::Load(const map::SavedMap& saved) {
  backend::PoseGraph graph = RestorePoseGraph(saved, pose_graph_options_);
  graph_ = std::move(graph);
  waiting_edges_.clear();
  loop_shared_points_.clear();  // their points went with the bundle adjuster
  bundle_adjuster_.reset();
  camera_ = saved.camera;  // keyframes of another camera are refused from now on
  localization_correction_.reset();
  next_starts_new_segment_ = true;
  last_graph_keyframe_time_.reset();
  for (const map::SavedKeyframe& keyframe : saved.keyframes) {
    loaded_below_ = std::max(loaded_below_, keyframe.keyframe.id + 1);
  }
  last_closed_keyframe_ = std::max(last_closed_keyframe_, loaded_below_ - 1);
}

void MappingStage::CheckGraph(const map::SavedMap& saved) {
  // Rebuilding does not depend on the optimisation's options.
  RestorePoseGraph(saved, backend::PoseGraphOptions());
}

Eigen::Isometry3d MappingStage::MapPose(std::int64_t id) const {
  if (!graph_.Contains(id)) {
    throw std::out_of_range("keyframe " + std::to_string(id) + " is not in the map");
  }
  return graph_.MapPose(id);
}

Eigen::Isometry3d MappingStage::MapToOdom() const {
  if (mode_ == SlamMode::kLocalization && localization_correction_) {
    return *localization_correction_;
  }
  return graph_.MapToOdom();
}

std::vector<backend::PoseGraphEdge> MappingStage::LoopEdges() const {
  std::vector<backend::PoseGraphEdge> edges = graph_.Edges();
  edges.erase(std::remove_if(edges.begin(), edges.end(),
                             [](const backend::PoseGraphEdge& edge) {
                               return edge.type == backend::PoseGraphEdgeType::kOdometry;
                             }),
              edges.end());
  return edges;
}

MapSnapshot MappingStage::Snapshot() const {
  MapSnapshot snapshot;
  for (const auto& [id, pose] : graph_.MapPoses()) {
    snapshot.keyframes[id] = {pose, graph_.InMap(id)};
  }
  snapshot.loop_edges = LoopEdges();
  snapshot.T_map_odom = MapToOdom();
  return snapshot;
}

}  // namespace stereo_fabmap_slam::pipeline
