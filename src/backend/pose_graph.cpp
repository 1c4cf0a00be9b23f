#include "stereo_fabmap_slam/backend/pose_graph.h"

#include <algorithm>
#include <cmath>
#include <deque>
#include <sstream>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include <ceres/ceres.h>
#include <Eigen/Cholesky>

#include "stereo_fabmap_slam/geometry/relative_pose_error.h"

namespace stereo_fabmap_slam::backend {
namespace {

constexpr double kPi = 3.14159265358979323846;

}  // namespace

Eigen::Isometry3d PoseGraph::Keyframe::MapPose() const {
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear() = q_map_camera.toRotationMatrix();
  T.translation() = t_map_camera;
  return T;
}

void PoseGraph::Keyframe::SetMapPose(const Eigen::Isometry3d& T_map_camera) {
  q_map_camera = Eigen::Quaterniond(T_map_camera.rotation()).normalized();
  t_map_camera = T_map_camera.translation();
}

PoseGraph::PoseGraph(const PoseGraphOptions& options) : options_((options.Validate(), options)) {
  const double rotation_sigma = options_.odometry_rotation_sigma_deg * kPi / 180.0;
  Eigen::Matrix<double, 6, 1> inverse_sigma;
  inverse_sigma << Eigen::Vector3d::Constant(1.0 / options_.odometry_translation_sigma),
      Eigen::Vector3d::Constant(1.0 / rotation_sigma);
  odometry_sqrt_information_ = inverse_sigma.asDiagonal();
  odometry_information_ = inverse_sigma.cwiseAbs2().asDiagonal();
}

void PoseGraph::AddKeyframe(std::int64_t id, const Eigen::Isometry3d& T_odom_camera,
                            bool starts_new_segment) {
  if (!keyframes_.empty() && id <= keyframes_.back().id) {
    throw std::invalid_argument("PoseGraph::AddKeyframe: id " + std::to_string(id) +
                                " is not above the last, " + std::to_string(keyframes_.back().id));
  }
  Keyframe keyframe;
  keyframe.id = id;
  keyframe.T_odom_camera = T_odom_camera;
  keyframe.step_information = odometry_information_;
  keyframe.step_sqrt_information = odometry_sqrt_information_;
  if (keyframes_.empty() || starts_new_segment) {
    // Nothing relates the new odometry frame to the old one; the newest correction is the best
    // guess there is, and it keeps the map pose continuous when odometry itself did not restart.
    const Eigen::Isometry3d T_map_odom = MapToOdom();
    keyframe.segment = static_cast<int>(segments_.size());
    segments_.push_back({keyframes_.size(), keyframe.segment, 0, T_map_odom});
    keyframe.SetMapPose(T_map_odom * T_odom_camera);
  } else {
    const Keyframe& previous = keyframes_.back();
    keyframe.segment = previous.segment;
    const Segment& piece = segments_[PieceOf(keyframe.segment)];
    if (piece.loops == 0) {
      // Exactly the odometry pose under the segment's correction, without rounding piling up.
      keyframe.SetMapPose(piece.T_map_odom * T_odom_camera);
    } else {
      // Corrected like its predecessor, so it is consistent before the next optimisation.
      keyframe.SetMapPose(previous.MapPose() * (previous.T_odom_camera.inverse() * T_odom_camera));
    }
  }
  keyframes_.push_back(keyframe);
}

void PoseGraph::UpdateOdometryCovariance(std::int64_t from, std::int64_t to,
                                         const Eigen::Matrix<double, 6, 6>& covariance) {
  if (!(options_.odometry_covariance_scale > 0) || !Contains(from) || !Contains(to)) return;
  const std::size_t i = IndexOf(to);
  if (i == 0 || keyframes_[i - 1].id != from || keyframes_[i - 1].segment != keyframes_[i].segment)
    return;
  Eigen::Matrix<double, 6, 6> scaled =
      options_.odometry_covariance_scale * 0.5 * (covariance + covariance.transpose());
  if (options_.odometry_covariance_plus_fixed) scaled += odometry_information_.inverse();
  const Eigen::LLT<Eigen::Matrix<double, 6, 6>> factor(scaled);
  if (factor.info() != Eigen::Success) return;
  const Eigen::Matrix<double, 6, 6> information =
      factor.solve(Eigen::Matrix<double, 6, 6>::Identity());
  const Eigen::LLT<Eigen::Matrix<double, 6, 6>> information_factor(
      0.5 * (information + information.transpose()));
  if (information_factor.info() != Eigen::Success) return;
  keyframes_[i].step_information = information;
  // S with S^T S = information: the transposed lower factor (RelativePoseError's convention).
  keyframes_[i].step_sqrt_information = information_factor.matrixL().transpose();
}

void PoseGraph::UpdateOdometryPose(std::int64_t id, const Eigen::Isometry3d& T_odom_camera) {
  const std::size_t index = IndexOf(id);
  Keyframe& keyframe = keyframes_[index];
  keyframe.T_odom_camera = T_odom_camera;
  // The window measured this keyframe again: its steps are the odometry's once more.
  keyframe.refined_step.reset();
  if (index + 1 < keyframes_.size()) keyframes_[index + 1].refined_step.reset();
  const Segment& piece = segments_[PieceOf(keyframe.segment)];
  if (piece.loops == 0) keyframe.SetMapPose(piece.T_map_odom * T_odom_camera);
}

bool PoseGraph::AddGap(std::int64_t to, double seconds) {
  const std::size_t index = IndexOf(to);
  if (index == 0 || keyframes_[index - 1].segment == keyframes_[index].segment) {
    throw std::invalid_argument("PoseGraph::AddGap: keyframe " + std::to_string(to) +
                                " does not start a segment after another keyframe");
  }
  if (!(seconds >= 0) || seconds > options_.gap_max_seconds) return false;
  Gap gap;
  gap.to = index;
  const double translation_sigma =
      options_.odometry_translation_sigma + options_.gap_translation_sigma_per_second * seconds;
  const double rotation_sigma = (options_.odometry_rotation_sigma_deg +
                                 options_.gap_rotation_sigma_deg_per_second * seconds) *
                                kPi / 180.0;
  Eigen::Matrix<double, 6, 1> inverse_sigma;
  inverse_sigma << Eigen::Vector3d::Constant(1.0 / translation_sigma),
      Eigen::Vector3d::Constant(1.0 / rotation_sigma);
  gap.sqrt_information = inverse_sigma.asDiagonal();
  gap.information = inverse_sigma.cwiseAbs2().asDiagonal();
  gaps_.push_back(gap);
  return true;
}

PoseGraph::Loop PoseGraph::GapEdge(const Gap& gap) const {
  const Keyframe& before = keyframes_[gap.to - 1];
  const Keyframe& after = keyframes_[gap.to];
  return Loop{gap.to - 1,
              gap.to,
              before.T_odom_camera.inverse() * after.T_odom_camera,
              gap.information,
              gap.sqrt_information,
              PoseGraphEdgeType::kOdometry};
}

void PoseGraph::AddLoop(const map::LoopEdge& edge, PoseGraphEdgeType type) {
  if (type == PoseGraphEdgeType::kOdometry) {
    throw std::invalid_argument("PoseGraph::AddLoop: odometry edges come from AddKeyframe");
  }
  Loop loop;
  loop.type = type;
  loop.match = IndexOf(edge.match_id);
  loop.query = IndexOf(edge.query_id);
  if (loop.match == loop.query) {
    throw std::invalid_argument("PoseGraph::AddLoop: keyframe " + std::to_string(edge.query_id) +
                                " cannot close a loop with itself");
  }
  loop.T_match_query = edge.T_match_query;
  loop.information = edge.information;
  const Eigen::LLT<Eigen::Matrix<double, 6, 6>> cholesky(edge.information);
  if (!edge.information.allFinite() || !edge.information.isApprox(edge.information.transpose()) ||
      cholesky.info() != Eigen::Success) {
    throw std::invalid_argument(
        "PoseGraph::AddLoop: information of the loop " + std::to_string(edge.match_id) + " -> " +
        std::to_string(edge.query_id) + " is not symmetric positive definite");
  }
  // information = L * L^T, so S = L^T gives |S * e|^2 = e^T * information * e.
  loop.sqrt_information = cholesky.matrixU();

  const int match_piece = PieceOf(keyframes_[loop.match].segment);
  const int query_piece = PieceOf(keyframes_[loop.query].segment);
  int piece = match_piece;
  if (match_piece != query_piece) {
    // The younger piece (higher root) moves, so the older one keeps its gauge.
    const int moving = std::max(match_piece, query_piece);
    piece = std::min(match_piece, query_piece);
    const Keyframe& match = keyframes_[loop.match];
    const Keyframe& query = keyframes_[loop.query];
    // Correction taking the moving keyframe of the edge to where the edge puts it.
    const Eigen::Isometry3d correction =
        moving == query_piece
            ? match.MapPose() * loop.T_match_query * query.MapPose().inverse()
            : query.MapPose() * loop.T_match_query.inverse() * match.MapPose().inverse();
    for (Keyframe& keyframe : keyframes_) {
      if (PieceOf(keyframe.segment) == moving) {
        keyframe.SetMapPose(correction * keyframe.MapPose());
      }
    }
    segments_[moving].parent = piece;
    segments_[piece].loops += segments_[moving].loops;
  }
  ++segments_[piece].loops;
  loops_.push_back(loop);
}

double PoseGraph::LoopChiSquare(const Loop& loop) const {
  const Keyframe& a = keyframes_[loop.match];
  const Keyframe& b = keyframes_[loop.query];
  const geometry::RelativePoseError error(loop.T_match_query, loop.sqrt_information);
  Eigen::Matrix<double, 6, 1> residual;
  error(a.q_map_camera.coeffs().data(), a.t_map_camera.data(), b.q_map_camera.coeffs().data(),
        b.t_map_camera.data(), residual.data());
  return residual.squaredNorm();
}

std::vector<bool> PoseGraph::WindowAroundLoops(std::size_t first_loop) const {
  std::vector<std::vector<std::size_t>> loop_partners(keyframes_.size());
  for (const Loop& loop : loops_) {
    loop_partners[loop.match].push_back(loop.query);
    loop_partners[loop.query].push_back(loop.match);
  }
  for (const Gap& gap : gaps_) {
    if (gap.state != Gap::State::kKept) continue;
    loop_partners[gap.to - 1].push_back(gap.to);
    loop_partners[gap.to].push_back(gap.to - 1);
  }
  std::vector<int> hops(keyframes_.size(), -1);
  std::deque<std::size_t> frontier;
  for (std::size_t l = first_loop; l < loops_.size(); ++l) {
    for (const std::size_t end : {loops_[l].match, loops_[l].query}) {
      if (hops[end] < 0) {
        hops[end] = 0;
        frontier.push_back(end);
      }
    }
  }
  std::size_t size = frontier.size();
  while (!frontier.empty() && size < static_cast<std::size_t>(options_.local_keyframes)) {
    const std::size_t i = frontier.front();
    frontier.pop_front();
    std::vector<std::size_t> neighbours = loop_partners[i];
    if (i > 0 && keyframes_[i - 1].segment == keyframes_[i].segment) neighbours.push_back(i - 1);
    if (i + 1 < keyframes_.size() && keyframes_[i + 1].segment == keyframes_[i].segment) {
      neighbours.push_back(i + 1);
    }
    for (const std::size_t n : neighbours) {
      if (hops[n] >= 0 || size == static_cast<std::size_t>(options_.local_keyframes)) continue;
      hops[n] = hops[i] + 1;
      frontier.push_back(n);
      ++size;
    }
  }
  std::vector<bool> window(keyframes_.size());
  for (std::size_t i = 0; i < keyframes_.size(); ++i) window[i] = hops[i] >= 0;
  return window;
}

std::vector<PoseGraph::GapChain> PoseGraph::GapChainsToTry() const {
  // The waiting gap into each segment (gaps join consecutive segments).
  std::vector<int> gap_into(segments_.size(), -1);
  for (std::size_t g = 0; g < gaps_.size(); ++g) {
    if (gaps_[g].state == Gap::State::kWaiting)
      gap_into[keyframes_[gaps_[g].to].segment] = static_cast<int>(g);
  }
  std::vector<GapChain> chains;
  const int segments = static_cast<int>(segments_.size());
  for (int start = 0; start < segments; ++start) {
    if (segments_[PieceOf(start)].loops == 0) continue;
    GapChain chain{{}, {}, PieceOf(start)};
    for (int s = start + 1; s < segments && gap_into[s] >= 0; ++s) {
      chain.gaps.push_back(static_cast<std::size_t>(gap_into[s]));
      if (PieceOf(s) == chain.piece) {
        chains.push_back(chain);
        start = s - 1;  // the next chain may start where this one ended
        break;
      }
      // Only restarts that failed at once, segments of one keyframe on their own. A longer
      // segment tracked on its own: its odometry placed it after the gap into it, and the gap out
      // of it would bend it by the motion model's error there (at corridor ends 10-20 degrees of
      // turn in 0.2-0.7 s that a constant velocity misses: on the per-seed office figure eight a
      // 13 s segment between two gaps took the closed trajectory from 3.4 to 6.0 cm). A piece
      // with loops of its own is not this cycle's to join.
      const std::size_t end = s + 1 < segments ? segments_[s + 1].first : keyframes_.size();
      if (PieceOf(s) != s || segments_[s].loops > 0 || end - segments_[s].first > 1) break;
      chain.segments.push_back(s);
    }
  }
  return chains;
}

PoseGraphSummary PoseGraph::Optimize() {
  PoseGraphSummary result;
  // Without loops every piece follows its odometry, which the map poses already do.
  if (loops_.empty()) return result;
  const std::vector<GapChain> chains = GapChainsToTry();
  // Gaps to try close a cycle through the piece: the whole of it moves.
  bool local = optimised_ && options_.local_keyframes > 0 && loops_optimised_ < loops_.size() &&
               chains.empty();
  for (std::size_t l = loops_optimised_; local && l < loops_.size(); ++l) {
    local = LoopChiSquare(loops_[l]) < options_.consistent_loop_chi2;
  }
  // Keyframes whose poses move: in a local optimisation the window around the new loops, else
  // every keyframe of a piece with loops. Edges with one end outside hold it fixed.
  std::vector<bool> moving;
  if (local) {
    moving = WindowAroundLoops(loops_optimised_);
  } else {
    moving.resize(keyframes_.size());
    for (std::size_t i = 0; i < keyframes_.size(); ++i) {
      moving[i] = segments_[PieceOf(keyframes_[i].segment)].loops > 0;
    }
  }
  // The segments within the chains move too; their poses are kept in case a chain is refused.
  std::vector<std::size_t> trying;
  std::vector<std::pair<std::size_t, Eigen::Isometry3d>> before;
  for (const GapChain& chain : chains) {
    trying.insert(trying.end(), chain.gaps.begin(), chain.gaps.end());
    for (std::size_t i = 0; i < keyframes_.size(); ++i) {
      if (std::find(chain.segments.begin(), chain.segments.end(), keyframes_[i].segment) ==
          chain.segments.end())
        continue;
      moving[i] = true;
      before.emplace_back(i, keyframes_[i].MapPose());
    }
  }
  Solve(moving, trying, &result);
  // A chain stays if the optimised map agrees with each of its gaps (its segments join the
  // piece); if not (a kidnap), its segments go back to where they were, on their own, and the
  // map is solved again without it, from where the odometry and loops alone put it.
  bool refused = false;
  for (const GapChain& chain : chains) {
    bool agrees = true;
    for (const std::size_t g : chain.gaps)
      agrees = agrees && LoopChiSquare(GapEdge(gaps_[g])) < options_.gap_chi2;
    for (const std::size_t g : chain.gaps)
      gaps_[g].state = agrees ? Gap::State::kKept : Gap::State::kRefused;
    if (agrees) {
      for (const int s : chain.segments) segments_[s].parent = chain.piece;
      continue;
    }
    refused = true;
    for (const auto& [i, pose] : before) {
      if (std::find(chain.segments.begin(), chain.segments.end(), keyframes_[i].segment) ==
          chain.segments.end())
        continue;
      keyframes_[i].SetMapPose(pose);
      moving[i] = false;
    }
  }
  if (refused) {
    PoseGraphSummary again;
    Solve(moving, {}, &again);
    result.converged = again.converged;
    result.iterations += again.iterations;
    result.final_cost = again.final_cost;
  }
  loops_optimised_ = loops_.size();
  optimised_ = true;
  result.local = local;
  return result;
}

void PoseGraph::Solve(const std::vector<bool>& moving, const std::vector<std::size_t>& trying,
                      PoseGraphSummary* result) {
  // Shared by all residual blocks, hence not owned by the problem.
  ceres::EigenQuaternionManifold quaternion_manifold;
  ceres::CauchyLoss loop_loss(options_.loop_loss_scale);
  ceres::Problem::Options problem_options;
  problem_options.loss_function_ownership = ceres::DO_NOT_TAKE_OWNERSHIP;
  problem_options.manifold_ownership = ceres::DO_NOT_TAKE_OWNERSHIP;
  ceres::Problem problem(problem_options);
  for (std::size_t i = 1; i < keyframes_.size(); ++i) {
    Keyframe& a = keyframes_[i - 1];
    Keyframe& b = keyframes_[i];
    if (a.segment != b.segment || !(moving[i - 1] || moving[i])) continue;
    problem.AddResidualBlock(geometry::RelativePoseError::Create(Step(i), b.step_sqrt_information),
                             nullptr, a.q_map_camera.coeffs().data(), a.t_map_camera.data(),
                             b.q_map_camera.coeffs().data(), b.t_map_camera.data());
  }
  // Gaps kept and tried have the loops' robust loss: a wrong one pulls little before it is
  // refused.
  std::vector<Loop> edges = loops_;
  for (const Gap& gap : gaps_) {
    if (gap.state == Gap::State::kKept) edges.push_back(GapEdge(gap));
  }
  for (const std::size_t g : trying) edges.push_back(GapEdge(gaps_[g]));
  for (const Loop& loop : edges) {
    if (!(moving[loop.match] || moving[loop.query])) continue;
    Keyframe& a = keyframes_[loop.match];
    Keyframe& b = keyframes_[loop.query];
    problem.AddResidualBlock(
        geometry::RelativePoseError::Create(loop.T_match_query, loop.sqrt_information), &loop_loss,
        a.q_map_camera.coeffs().data(), a.t_map_camera.data(), b.q_map_camera.coeffs().data(),
        b.t_map_camera.data());
  }
  result->moved_keyframes = 0;
  for (std::size_t i = 0; i < keyframes_.size(); ++i) {
    double* rotation = keyframes_[i].q_map_camera.coeffs().data();
    if (!problem.HasParameterBlock(rotation)) continue;
    problem.SetManifold(rotation, &quaternion_manifold);
    if (!moving[i]) {
      problem.SetParameterBlockConstant(rotation);
      problem.SetParameterBlockConstant(keyframes_[i].t_map_camera.data());
    } else {
      ++result->moved_keyframes;
    }
  }
  // Gauge: each piece's oldest keyframe, the first of its root segment. (A local window
  // that does not reach it is held by the fixed keyframes around it.)
  for (std::size_t s = 0; s < segments_.size(); ++s) {
    if (segments_[s].parent != static_cast<int>(s) || segments_[s].loops == 0) continue;
    Keyframe& oldest = keyframes_[segments_[s].first];
    if (!moving[segments_[s].first] || !problem.HasParameterBlock(oldest.t_map_camera.data())) {
      continue;
    }
    problem.SetParameterBlockConstant(oldest.q_map_camera.coeffs().data());
    problem.SetParameterBlockConstant(oldest.t_map_camera.data());
    --result->moved_keyframes;
  }
  ceres::Solver::Options solver_options;
  // Each pose couples to its neighbours and a few loop partners: a very sparse normal matrix
  // that a fill-reducing sparse Cholesky factors in a few milliseconds per iteration.
  solver_options.linear_solver_type = ceres::SPARSE_NORMAL_CHOLESKY;
  solver_options.max_num_iterations = options_.iterations;
  solver_options.num_threads = 1;
  solver_options.logging_type = ceres::SILENT;
  ceres::Solver::Summary summary;
  ceres::Solve(solver_options, &problem, &summary);
  for (std::size_t i = 0; i < keyframes_.size(); ++i) {
    if (moving[i]) keyframes_[i].q_map_camera.normalize();
  }
  result->converged = summary.termination_type == ceres::CONVERGENCE;
  result->iterations = summary.num_successful_steps + summary.num_unsuccessful_steps;
  result->initial_cost = summary.initial_cost;
  result->final_cost = summary.final_cost;
}

bool PoseGraph::Contains(std::int64_t id) const {
  const auto it = std::lower_bound(keyframes_.begin(), keyframes_.end(), id,
                                   [](const Keyframe& k, std::int64_t i) { return k.id < i; });
  return it != keyframes_.end() && it->id == id;
}

Eigen::Isometry3d PoseGraph::MapPose(std::int64_t id) const {
  return keyframes_[IndexOf(id)].MapPose();
}

std::map<std::int64_t, Eigen::Isometry3d> PoseGraph::MapPoses() const {
  std::map<std::int64_t, Eigen::Isometry3d> poses;
  for (const Keyframe& keyframe : keyframes_) {
    poses.emplace_hint(poses.end(), keyframe.id, keyframe.MapPose());
  }
  return poses;
}

Eigen::Isometry3d PoseGraph::MapToOdom() const {
  if (keyframes_.empty()) return Eigen::Isometry3d::Identity();
  const Keyframe& newest = keyframes_.back();
  return newest.MapPose() * newest.T_odom_camera.inverse();
}

std::vector<PoseGraphEdge> PoseGraph::Edges() const {
  std::vector<PoseGraphEdge> edges;
  for (std::size_t i = 1; i < keyframes_.size(); ++i) {
    const Keyframe& a = keyframes_[i - 1];
    const Keyframe& b = keyframes_[i];
    if (a.segment != b.segment) continue;
    edges.push_back({a.id, b.id, Step(i), b.step_information, PoseGraphEdgeType::kOdometry});
  }
  for (const Gap& gap : gaps_) {
    if (gap.state != Gap::State::kKept) continue;
    const Loop edge = GapEdge(gap);
    edges.push_back({keyframes_[edge.match].id, keyframes_[edge.query].id, edge.T_match_query,
                     edge.information, PoseGraphEdgeType::kOdometry});
  }
  for (const Loop& loop : loops_) {
    edges.push_back({keyframes_[loop.match].id, keyframes_[loop.query].id, loop.T_match_query,
                     loop.information, loop.type});
  }
  return edges;
}

std::size_t PoseGraph::IndexOf(std::int64_t id) const {
  const auto it = std::lower_bound(keyframes_.begin(), keyframes_.end(), id,
                                   [](const Keyframe& k, std::int64_t i) { return k.id < i; });
  if (it == keyframes_.end() || it->id != id) {
    throw std::invalid_argument("PoseGraph: unknown keyframe id " + std::to_string(id));
  }
  return static_cast<std::size_t>(it - keyframes_.begin());
}

void PoseGraph::RestoreMapPose(std::int64_t id, const Eigen::Isometry3d& T_map_camera) {
  keyframes_[IndexOf(id)].SetMapPose(T_map_camera);
}

void PoseGraph::AdoptRefinement(const std::map<std::int64_t, Eigen::Isometry3d>& T_map_camera) {
  for (const auto& [id, pose] : T_map_camera) static_cast<void>(IndexOf(id));  // known, first
  for (const auto& [id, pose] : T_map_camera) keyframes_[IndexOf(id)].SetMapPose(pose);
  for (std::size_t i = 1; i < keyframes_.size(); ++i) {
    Keyframe& a = keyframes_[i - 1];
    Keyframe& b = keyframes_[i];
    if (a.segment == b.segment && T_map_camera.count(a.id) && T_map_camera.count(b.id)) {
      b.refined_step = a.MapPose().inverse() * b.MapPose();
    }
  }
}

Eigen::Isometry3d PoseGraph::Step(std::size_t index) const {
  const Keyframe& b = keyframes_[index];
  return b.refined_step ? *b.refined_step
                        : keyframes_[index - 1].T_odom_camera.inverse() * b.T_odom_camera;
}

bool PoseGraph::Connected(std::int64_t a, std::int64_t b) const {
  return PieceOf(keyframes_[IndexOf(a)].segment) == PieceOf(keyframes_[IndexOf(b)].segment);
}

bool PoseGraph::InMap(std::int64_t id) const {
  return Contains(id) && Connected(id, keyframes_.front().id);
}

int PoseGraph::PieceOf(int segment) const {
  // No path compression: there is one segment per tracking loss, so the chains stay short.
  while (segments_[segment].parent != segment) segment = segments_[segment].parent;
  return segment;
}

}  // namespace stereo_fabmap_slam::backend
