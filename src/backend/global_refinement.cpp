#include "stereo_fabmap_slam/backend/global_refinement.h"

#include <algorithm>
#include <cmath>
#include <memory>
#include <set>
#include <utility>

#include <ceres/ceres.h>
#include <Eigen/Cholesky>

#include "stereo_fabmap_slam/geometry/chi_square.h"
#include "stereo_fabmap_slam/geometry/pose_parameters.h"
#include "stereo_fabmap_slam/geometry/relative_pose_error.h"
#include "stereo_fabmap_slam/geometry/reprojection_error.h"

namespace stereo_fabmap_slam::backend {
namespace {

// The pose graph's relative pose error for poses kept as T_camera_map (the reprojections'
// parameters): each inverted, then the graph's own residual.
class EdgeOfCameraPoses {
 public:
  EdgeOfCameraPoses(const Eigen::Isometry3d& T_a_b, const Eigen::Matrix<double, 6, 6>& sqrt_info)
      : error_(T_a_b, sqrt_info) {}

  static ceres::CostFunction* Create(const PoseGraphEdge& edge) {
    const Eigen::Matrix<double, 6, 6> sqrt_information =
        edge.information.llt().matrixL().transpose();
    return new ceres::AutoDiffCostFunction<EdgeOfCameraPoses, 6, 4, 3, 4, 3>(
        new EdgeOfCameraPoses(edge.T_from_to, sqrt_information));
  }

  template <typename T>
  bool operator()(const T* rotation_a, const T* translation_a, const T* rotation_b,
                  const T* translation_b, T* residuals) const {
    Eigen::Quaternion<T> q_map_a, q_map_b;
    Eigen::Matrix<T, 3, 1> t_map_a, t_map_b;
    Invert(rotation_a, translation_a, &q_map_a, &t_map_a);
    Invert(rotation_b, translation_b, &q_map_b, &t_map_b);
    return error_(q_map_a.coeffs().data(), t_map_a.data(), q_map_b.coeffs().data(), t_map_b.data(),
                  residuals);
  }

 private:
  template <typename T>
  static void Invert(const T* rotation, const T* translation, Eigen::Quaternion<T>* q_inverse,
                     Eigen::Matrix<T, 3, 1>* t_inverse) {
    const Eigen::Map<const Eigen::Quaternion<T>> q(rotation);
    const Eigen::Map<const Eigen::Matrix<T, 3, 1>> t(translation);
    *q_inverse = q.conjugate();
    *t_inverse = -(*q_inverse * t);
  }

  geometry::RelativePoseError error_;
};

}  // namespace

GlobalRefinement::GlobalRefinement(const GlobalRefinementOptions& options,
                                   const PoseGraphOptions& graph_options,
                                   const geometry::StereoCamera& camera, double sigma)
    : options_((options.Validate(), options)),
      graph_options_(graph_options),
      camera_(camera),
      sigma_(sigma) {}

void GlobalRefinement::AddKeyframe(std::int64_t id, const Eigen::Isometry3d& T_map_camera,
                                   bool fixed) {
  const geometry::PoseParameters parameters =
      geometry::PoseParameters::FromTransform(T_map_camera.inverse());
  Pose& pose = poses_[id];
  std::copy(parameters.rotation, parameters.rotation + 4, pose.rotation);
  std::copy(parameters.translation, parameters.translation + 3, pose.translation);
  pose.fixed = fixed;
}

void GlobalRefinement::AddPoint(const Eigen::Vector3d& point_map,
                                const std::vector<Observation>& observations) {
  Point point{point_map, {}};
  for (const Observation& o : observations) {
    if (poses_.count(o.keyframe)) point.observations.push_back(o);
  }
  if (point.observations.size() >= 2) points_.push_back(std::move(point));
}

void GlobalRefinement::AddEdge(const PoseGraphEdge& edge) {
  if (!poses_.count(edge.from) || !poses_.count(edge.to)) return;
  edges_.push_back(edge);
  if (edge.type != PoseGraphEdgeType::kOdometry) {
    edges_.back().information *= options_.loop_information_scale;
  }
}

void GlobalRefinement::DropOdometryEdgesThePointsHold() {
  std::map<std::pair<std::int64_t, std::int64_t>, int> shared;  // per odometry edge
  for (const PoseGraphEdge& edge : edges_) {
    if (edge.type == PoseGraphEdgeType::kOdometry) shared[{edge.from, edge.to}] = 0;
  }
  std::vector<std::int64_t> seen_by;
  for (const Point& point : points_) {
    seen_by.clear();
    for (const Observation& o : point.observations) seen_by.push_back(o.keyframe);
    std::sort(seen_by.begin(), seen_by.end());
    for (std::size_t a = 0; a < seen_by.size(); ++a) {
      for (std::size_t b = a + 1; b < seen_by.size(); ++b) {
        for (const auto& pair : {std::pair{seen_by[a], seen_by[b]}, {seen_by[b], seen_by[a]}}) {
          const auto count = shared.find(pair);
          if (count != shared.end()) ++count->second;
        }
      }
    }
  }
  edges_.erase(std::remove_if(edges_.begin(), edges_.end(),
                              [&](const PoseGraphEdge& edge) {
                                return edge.type == PoseGraphEdgeType::kOdometry &&
                                       shared.at({edge.from, edge.to}) >=
                                           options_.odometry_edge_below_shared_points;
                              }),
               edges_.end());
}

GlobalRefinementSummary GlobalRefinement::Solve() {
  DropOdometryEdgesThePointsHold();
  GlobalRefinementSummary result;
  std::size_t observations = 0;
  for (const Point& point : points_) observations += point.observations.size();
  // Owned here rather than by the problem: one array for every round.
  std::vector<geometry::ReprojectionCost> costs(observations);
  std::vector<std::unique_ptr<ceres::CostFunction>> edge_costs;
  for (const PoseGraphEdge& edge : edges_) edge_costs.emplace_back(EdgeOfCameraPoses::Create(edge));
  ceres::HuberLoss reprojection_loss(std::sqrt(geometry::kChiSquare95ThreeDof));
  ceres::CauchyLoss loop_loss(graph_options_.loop_loss_scale);

  std::set<std::pair<std::size_t, std::size_t>> rejected;  // (point, observation)
  for (int round = 0; round < options_.rounds; ++round) {
    ceres::Problem::Options problem_options;
    problem_options.loss_function_ownership = ceres::DO_NOT_TAKE_OWNERSHIP;
    problem_options.cost_function_ownership = ceres::DO_NOT_TAKE_OWNERSHIP;
    ceres::Problem problem(problem_options);
    auto ordering = std::make_shared<ceres::ParameterBlockOrdering>();
    std::size_t next_cost = 0;
    result.observations = 0;
    result.points = 0;
    for (std::size_t p = 0; p < points_.size(); ++p) {
      Point& point = points_[p];
      int used = 0;
      for (std::size_t i = 0; i < point.observations.size(); ++i) {
        if (rejected.count({p, i})) continue;
        const Observation& o = point.observations[i];
        Pose& pose = poses_.at(o.keyframe);
        geometry::ReprojectionCost& cost = costs[next_cost++];
        cost.Set(camera_, o.u, o.v, o.u_right, sigma_);
        problem.AddResidualBlock(&cost, &reprojection_loss, pose.rotation, pose.translation,
                                 point.position.data());
        ++used;
      }
      if (used > 0) {
        ordering->AddElementToGroup(point.position.data(), 0);
        ++result.points;
        result.observations += used;
      }
    }
    for (std::size_t e = 0; e < edges_.size(); ++e) {
      Pose& from = poses_.at(edges_[e].from);
      Pose& to = poses_.at(edges_[e].to);
      problem.AddResidualBlock(
          edge_costs[e].get(),
          edges_[e].type == PoseGraphEdgeType::kOdometry ? nullptr : &loop_loss, from.rotation,
          from.translation, to.rotation, to.translation);
    }
    result.edges = edges_.size();
    result.keyframes = 0;
    for (auto& [id, pose] : poses_) {
      if (!problem.HasParameterBlock(pose.rotation)) continue;
      problem.SetManifold(pose.rotation, new ceres::EigenQuaternionManifold);
      ordering->AddElementToGroup(pose.rotation, 1);
      ordering->AddElementToGroup(pose.translation, 1);
      if (pose.fixed) {
        problem.SetParameterBlockConstant(pose.rotation);
        problem.SetParameterBlockConstant(pose.translation);
      } else {
        ++result.keyframes;
      }
    }
    if (result.keyframes == 0) return result;

    ceres::Solver::Options solver_options;
    // Hundreds of cameras, each seeing its neighbours' points and a few loops: a sparse reduced
    // camera system.
    solver_options.linear_solver_type = ceres::SPARSE_SCHUR;
    solver_options.linear_solver_ordering = ordering;
    solver_options.max_num_iterations = options_.iterations;
    solver_options.num_threads = options_.threads;
    solver_options.logging_type = ceres::SILENT;
    ceres::Solver::Summary summary;
    ceres::Solve(solver_options, &problem, &summary);
    if (round == 0) result.initial_cost = summary.initial_cost;
    result.final_cost = summary.final_cost;
    result.iterations += static_cast<int>(summary.iterations.size()) - 1;
    result.converged = summary.termination_type == ceres::CONVERGENCE;

    const std::size_t rejected_before = rejected.size();
    for (std::size_t p = 0; p < points_.size(); ++p) {
      const Point& point = points_[p];
      for (std::size_t i = 0; i < point.observations.size(); ++i) {
        const Observation& o = point.observations[i];
        const double chi2 =
            geometry::SquaredReprojectionError(camera_, poses_.at(o.keyframe).CameraFromMap(),
                                               point.position, o.u, o.v, o.u_right, sigma_);
        if (!(chi2 <
              (o.u_right >= 0 ? geometry::kChiSquare95ThreeDof : geometry::kChiSquare95TwoDof))) {
          rejected.insert({p, i});
        }
      }
    }
    if (rejected.size() == rejected_before) break;
  }
  return result;
}

Eigen::Isometry3d GlobalRefinement::Pose::CameraFromMap() const {
  geometry::PoseParameters parameters;
  std::copy(rotation, rotation + 4, parameters.rotation);
  std::copy(translation, translation + 3, parameters.translation);
  return parameters.ToTransform();
}

std::map<std::int64_t, Eigen::Isometry3d> GlobalRefinement::Poses() const {
  std::map<std::int64_t, Eigen::Isometry3d> poses;
  for (const auto& [id, pose] : poses_) poses[id] = pose.CameraFromMap().inverse();
  return poses;
}

}  // namespace stereo_fabmap_slam::backend
