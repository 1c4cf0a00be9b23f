#pragma once

#include <cstddef>
#include <cstdint>
#include <map>
#include <optional>
#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "stereo_fabmap_slam/backend/backend_options.h"
#include "stereo_fabmap_slam/map/loop_edge.h"

namespace stereo_fabmap_slam::backend {

// Odometry between consecutive keyframes of a segment; a verified loop between two keyframes;
// a relocalization: a frame of a segment cut off by tracking loss found in the map again.
enum class PoseGraphEdgeType { kOdometry, kLoop, kRelocalization };

struct PoseGraphEdge {
  std::int64_t from = -1;
  std::int64_t to = -1;
  Eigen::Isometry3d T_from_to = Eigen::Isometry3d::Identity();
  // Order (translation, rotation) of geometry::RelativePoseError's residual.
  Eigen::Matrix<double, 6, 6> information = Eigen::Matrix<double, 6, 6>::Identity();
  PoseGraphEdgeType type = PoseGraphEdgeType::kOdometry;
};

struct PoseGraphSummary {
  bool converged = true;
  int iterations = 0;       // 0: nothing to optimise (no loop edges)
  double initial_cost = 0;  // Ceres' cost, half the sum of squared whitened (robustified) errors
  double final_cost = 0;    // (of the edges in the problem: the window's when local)
  bool local = false;       // only keyframes near the new loops moved (see Optimize())
  std::size_t moved_keyframes = 0;  // keyframes whose poses were optimised
};

// Keyframe poses in a map frame made consistent by loop closures. Nodes: keyframes, whose
// poses T_map_camera are optimised. Edges: odometry between consecutive keyframes of a segment
// (what the tracker measured, from the latest odometry poses) and loop edges (verified
// revisits, with a Cauchy loss). Segments are runs of keyframes with unbroken tracking; loop
// edges join them into pieces, each with its own gauge: its oldest keyframe stays fixed.
// A piece without loops has nothing to correct: its poses are its odometry poses under the
// fixed correction it was started with, and Optimize() leaves it out of the problem.
// Not thread-safe; no clock, no global state.
class PoseGraph {
 public:
  explicit PoseGraph(const PoseGraphOptions& options);  // throws std::invalid_argument

  // Keyframes arrive in increasing id order with their pose in the odometry frame (odom).
  // starts_new_segment: tracking was lost before it; no odometry edge joins it to the previous
  // keyframe, so it begins a new, unconnected segment until a loop edge joins the segments.
  // Its map pose: the previous keyframe's map pose times the odometry step, or for a new segment
  // MapToOdom() * T_odom_camera. Throws std::invalid_argument if id is not above the last.
  void AddKeyframe(std::int64_t id, const Eigen::Isometry3d& T_odom_camera,
                   bool starts_new_segment);
  // Bundle adjustment moved a keyframe in odom: the odometry edges touching it follow (at the
  // next Optimize(), or at once in a piece without loops). Throws for unknown ids.
  void UpdateOdometryPose(std::int64_t id, const Eigen::Isometry3d& T_odom_camera);
  // The bundle adjustment's covariance of the step from keyframe `from` to `to`: with
  // options.odometry_covariance_scale > 0, the odometry edge between them carries it (scaled)
  // instead of the fixed sigmas. Ignored if the two are not consecutive keyframes of one
  // segment, if either is unknown, or if the covariance is not positive definite.
  void UpdateOdometryCovariance(std::int64_t from, std::int64_t to,
                                const Eigen::Matrix<double, 6, 6>& covariance);
  // Throws std::invalid_argument for unknown ids, a loop of a keyframe with itself, or an
  // information matrix that is not symmetric positive definite. A loop joining two pieces
  // moves the younger one rigidly onto the older one through this edge at once, so that the edge
  // starts the optimisation satisfied instead of hundreds of sigmas off, where its robust loss
  // would ignore it.
  // `type`: kLoop or kRelocalization (the same constraint; kept apart for display and counts).
  void AddLoop(const map::LoopEdge& loop, PoseGraphEdgeType type = PoseGraphEdgeType::kLoop);
  // A tracking loss's gap: keyframe `to` starts a segment because tracking was lost, after the
  // keyframe before it, `seconds` earlier; the odometry bridged the loss by its motion model, so
  // the two odometry poses are related, more loosely than by tracking (the gap's uncertainty
  // grows with `seconds`). Nothing joins the segments for it: relocalization and loops decide
  // where the new segment is. Once they have joined the two pieces (directly, or through
  // restarts of one keyframe between, each with its gap), the next Optimize() adds the gaps as
  // edges and keeps them if the optimised map agrees with each (options.gap_chi2), so the new
  // segment's start follows the motion model instead of hanging loose from the loop that joined
  // it far later. A kidnap disagrees by metres and is taken out. A saved map keeps the poses,
  // not the gaps (LoopEdges() holds loop and relocalization edges only). Gaps longer than
  // options.gap_max_seconds are ignored; returns whether the gap was kept. Throws
  // std::invalid_argument if `to` is unknown or does not start a segment after another keyframe.
  bool AddGap(std::int64_t to, double seconds);
  // Sets a keyframe's map pose as a saved map had it (after AddKeyframe and AddLoop have rebuilt
  // the graph); throws for unknown ids.
  void RestoreMapPose(std::int64_t id, const Eigen::Isometry3d& T_map_camera);
  // A refinement of the whole map (GlobalRefinement) put these keyframes here (T_map_camera):
  // they take these map poses, and each odometry edge between two of them (consecutive
  // keyframes of a segment) measures the refined step instead of the odometry's, so that later
  // optimisations start from the refinement and keep it where no new loop says otherwise. Once
  // the bundle adjustment moves a keyframe again (UpdateOdometryPose), its two edges measure the
  // odometry's steps again. Throws std::invalid_argument for unknown ids.
  void AdoptRefinement(const std::map<std::int64_t, Eigen::Isometry3d>& T_map_camera);
  // Optimises the pieces that have loops, from the current map poses. When every loop added
  // since the last Optimize() already agrees with the map (its squared whitened error below
  // options.consistent_loop_chi2), only the options.local_keyframes keyframes nearest those
  // loops in the graph move, against their fixed neighbours: such a loop corrects little, and
  // near it. On a route driven again and again a loop comes with nearly every keyframe, and
  // optimising the whole graph for each grows with the laps. The first Optimize(), a loop that
  // disagrees, and local_keyframes 0 optimise every piece with loops.
  PoseGraphSummary Optimize();

  bool Contains(std::int64_t id) const;
  // Whether loop or relocalization edges join the two keyframes' segments (one map); throws
  // std::invalid_argument for unknown ids.
  bool Connected(std::int64_t a, std::int64_t b) const;
  // Whether the keyframe is joined to the graph's first keyframe (the map's anchor): in the map,
  // not in a piece of its own. False for an unknown id.
  bool InMap(std::int64_t id) const;
  Eigen::Isometry3d MapPose(std::int64_t id) const;  // T_map_camera; throws for unknown ids
  std::map<std::int64_t, Eigen::Isometry3d> MapPoses() const;
  // T_map_odom: the correction of the newest keyframe, map pose * odom pose^-1, what a ROS
  // backend broadcasts as tf map -> odom. Identity while the graph is empty.
  Eigen::Isometry3d MapToOdom() const;
  // Odometry edges (from the latest odometry poses; gaps the map agreed with among them, with
  // their own information), then loop edges (from: match, to: query).
  std::vector<PoseGraphEdge> Edges() const;
  std::size_t size() const { return keyframes_.size(); }
  std::int64_t last_id() const { return keyframes_.empty() ? -1 : keyframes_.back().id; }

 private:
  struct Keyframe {
    std::int64_t id;
    int segment;
    Eigen::Isometry3d T_odom_camera;
    // T_map_camera, kept as Ceres parameter blocks so that Optimize() starts from the last
    // solution and writes into place.
    Eigen::Quaterniond q_map_camera;
    Eigen::Vector3d t_map_camera;
    // Information of the odometry edge from the keyframe before (the same segment's), and its
    // square root: the fixed sigmas' unless UpdateOdometryCovariance gave the step's own.
    Eigen::Matrix<double, 6, 6> step_information;
    Eigen::Matrix<double, 6, 6> step_sqrt_information;
    // T_previous_this as a refinement of the whole map found it (AdoptRefinement), measured by
    // the odometry edge from the keyframe before in place of the odometry poses' step.
    std::optional<Eigen::Isometry3d> refined_step;

    Eigen::Isometry3d MapPose() const;
    void SetMapPose(const Eigen::Isometry3d& T_map_camera);
  };
  struct Loop {
    std::size_t match, query;  // indices into keyframes_
    Eigen::Isometry3d T_match_query;
    Eigen::Matrix<double, 6, 6> information;
    Eigen::Matrix<double, 6, 6> sqrt_information;
    PoseGraphEdgeType type;
  };
  // A tracking loss's gap, from the keyframe before the loss (index to - 1) to `to`.
  struct Gap {
    enum class State { kWaiting, kKept, kRefused };
    std::size_t to;
    Eigen::Matrix<double, 6, 6> information, sqrt_information;
    State state = State::kWaiting;
  };
  struct Segment {
    std::size_t first;  // index of its first keyframe
    // Union-find over segments: pieces are segments joined by loops. The root is the
    // oldest segment of the piece, whose first keyframe is the piece's gauge.
    int parent;
    int loops;  // loop edges in the piece (valid at the root)
    // Map pose = T_map_odom * odometry pose while the piece has no loops.
    Eigen::Isometry3d T_map_odom;
  };

  std::size_t IndexOf(std::int64_t id) const;  // throws std::invalid_argument
  // What the odometry edge into keyframes_[index] (from the one before, same segment) measures.
  Eigen::Isometry3d Step(std::size_t index) const;
  int PieceOf(int segment) const;  // the root segment
  // The squared whitened error of a loop at the current map poses.
  double LoopChiSquare(const Loop& loop) const;
  // A gap as an edge, from the latest odometry poses.
  Loop GapEdge(const Gap& gap) const;
  // Waiting gaps that lead from a piece with loops, through segments of one keyframe that are
  // pieces of their own (a loss during which the odometry restarted several times), back into
  // the same piece: a cycle that loops closed, to try at the next Optimize().
  struct GapChain {
    std::vector<std::size_t> gaps;  // indices into gaps_, in order
    std::vector<int> segments;      // the segments between (may be none)
    int piece;                      // the root segment of the piece at both ends
  };
  std::vector<GapChain> GapChainsToTry() const;
  // Builds and solves the problem over the `moving` keyframes (the others held fixed), with the
  // gaps kept and those `trying` (indices into gaps_); fills the result's counts and costs.
  void Solve(const std::vector<bool>& moving, const std::vector<std::size_t>& trying,
             PoseGraphSummary* result);
  // The options_.local_keyframes keyframes (by index) nearest the loops from index first_loop on,
  // in edges (odometry or loop), breadth first.
  std::vector<bool> WindowAroundLoops(std::size_t first_loop) const;

  PoseGraphOptions options_;
  Eigen::Matrix<double, 6, 6> odometry_information_;
  Eigen::Matrix<double, 6, 6> odometry_sqrt_information_;
  std::vector<Keyframe> keyframes_;  // by increasing id
  std::vector<Loop> loops_;
  std::vector<Gap> gaps_;
  std::vector<Segment> segments_;
  std::size_t loops_optimised_ = 0;  // loops_[0, loops_optimised_) were in an Optimize()
  bool optimised_ = false;           // an Optimize() has run over every piece with loops
};

}  // namespace stereo_fabmap_slam::backend
