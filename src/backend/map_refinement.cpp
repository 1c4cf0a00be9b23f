#include "stereo_fabmap_slam/backend/map_refinement.h"

#include <cmath>
#include <set>
#include <utility>

#include <ceres/ceres.h>

#include "stereo_fabmap_slam/geometry/chi_square.h"
#include "stereo_fabmap_slam/geometry/pose_parameters.h"
#include "stereo_fabmap_slam/geometry/relative_pose_error.h"
#include "stereo_fabmap_slam/geometry/reprojection_error.h"

namespace stereo_fabmap_slam::backend {
namespace {

// A loop edge between two keyframes whose parameters are T_camera_map (the reprojection's
// blocks): the pose graph's error of T_map_a, T_map_b.
class LoopEdgeError {
 public:
  LoopEdgeError(const Eigen::Isometry3d& T_a_b, const Eigen::Matrix<double, 6, 6>& sqrt_information)
      : error_(T_a_b, sqrt_information) {}

  template <typename T>
  bool operator()(const T* rotation_a, const T* translation_a, const T* rotation_b,
                  const T* translation_b, T* residuals) const {
    const Eigen::Quaternion<T> q_map_a =
        Eigen::Map<const Eigen::Quaternion<T>>(rotation_a).conjugate();
    const Eigen::Matrix<T, 3, 1> t_map_a =
        -(q_map_a * Eigen::Map<const Eigen::Matrix<T, 3, 1>>(translation_a));
    const Eigen::Quaternion<T> q_map_b =
        Eigen::Map<const Eigen::Quaternion<T>>(rotation_b).conjugate();
    const Eigen::Matrix<T, 3, 1> t_map_b =
        -(q_map_b * Eigen::Map<const Eigen::Matrix<T, 3, 1>>(translation_b));
    return error_(q_map_a.coeffs().data(), t_map_a.data(), q_map_b.coeffs().data(), t_map_b.data(),
                  residuals);
  }

 private:
  geometry::RelativePoseError error_;
};

}  // namespace

RefinementResult MapRefinement::Refine(const Options& options, const geometry::StereoCamera& camera,
                                       const std::map<std::int64_t, RefinementKeyframe>& keyframes,
                                       const std::vector<PointTrack>& tracks,
                                       const std::vector<PoseGraphEdge>& loop_edges) {
  RefinementResult result;
  // Observations per keyframe decide which keyframes can move.
  std::map<std::int64_t, std::size_t> observations;
  for (const PointTrack& track : tracks) {
    for (const PointTrack::Observation& o : track.observations) {
      if (keyframes.count(o.keyframe)) ++observations[o.keyframe];
    }
  }
  std::map<std::int64_t, geometry::PoseParameters> poses;  // T_camera_map
  std::set<std::int64_t> moving;
  for (const auto& [id, keyframe] : keyframes) {
    poses[id] = geometry::PoseParameters::FromTransform(keyframe.T_map_camera.inverse());
    const auto seen = observations.find(id);
    if (!keyframe.fixed && seen != observations.end() &&
        seen->second >= static_cast<std::size_t>(options.min_observations)) {
      moving.insert(id);
    }
  }
  if (moving.empty()) return result;

  // Points in the map frame, through the correction of their first keyframe of the problem.
  struct Point {
    Eigen::Vector3d position;
    std::vector<PointTrack::Observation> observations;
  };
  std::vector<Point> points;
  points.reserve(tracks.size());
  for (const PointTrack& track : tracks) {
    Point point;
    for (const PointTrack::Observation& o : track.observations) {
      if (keyframes.count(o.keyframe)) point.observations.push_back(o);
    }
    if (point.observations.size() < 2) continue;
    const RefinementKeyframe& anchor = keyframes.at(point.observations.front().keyframe);
    point.position = anchor.T_map_camera * (anchor.T_odom_camera.inverse() * track.position);
    points.push_back(std::move(point));
  }

  ceres::HuberLoss reprojection_loss(std::sqrt(geometry::kChiSquare95ThreeDof));
  ceres::CauchyLoss loop_loss(options.loop_loss_scale);
  ceres::EigenQuaternionManifold quaternion_manifold;
  std::set<std::pair<std::size_t, std::int64_t>> rejected;  // (point, keyframe)
  for (int round = 0; round < options.rounds; ++round) {
    ceres::Problem::Options problem_options;
    problem_options.loss_function_ownership = ceres::DO_NOT_TAKE_OWNERSHIP;
    problem_options.manifold_ownership = ceres::DO_NOT_TAKE_OWNERSHIP;
    ceres::Problem problem(problem_options);
    result.summary.observations = 0;
    for (std::size_t p = 0; p < points.size(); ++p) {
      for (const PointTrack::Observation& o : points[p].observations) {
        if (rejected.count({p, o.keyframe})) continue;
        geometry::PoseParameters& pose = poses[o.keyframe];
        problem.AddResidualBlock(
            geometry::ReprojectionError::Create(camera, o.u, o.v, o.u_right, options.sigma),
            &reprojection_loss, pose.rotation, pose.translation, points[p].position.data());
        ++result.summary.observations;
      }
    }
    for (const PoseGraphEdge& edge : loop_edges) {
      const auto a = poses.find(edge.from), b = poses.find(edge.to);
      if (a == poses.end() || b == poses.end()) continue;
      if (!moving.count(edge.from) && !moving.count(edge.to)) continue;
      const Eigen::LLT<Eigen::Matrix<double, 6, 6>> cholesky(edge.information);
      problem.AddResidualBlock(new ceres::AutoDiffCostFunction<LoopEdgeError, 6, 4, 3, 4, 3>(
                                   new LoopEdgeError(edge.T_from_to, cholesky.matrixU())),
                               &loop_loss, a->second.rotation, a->second.translation,
                               b->second.rotation, b->second.translation);
    }
    for (auto& [id, pose] : poses) {
      if (!problem.HasParameterBlock(pose.rotation)) continue;
      problem.SetManifold(pose.rotation, &quaternion_manifold);
      if (!moving.count(id)) {
        problem.SetParameterBlockConstant(pose.rotation);
        problem.SetParameterBlockConstant(pose.translation);
      }
    }
    ceres::Solver::Options solver_options;
    // Hundreds of cameras with sparse covisibility: the reduced camera system is sparse.
    solver_options.linear_solver_type = ceres::SPARSE_SCHUR;
    solver_options.max_num_iterations = options.iterations;
    solver_options.num_threads = options.threads;
    solver_options.logging_type = ceres::SILENT;
    ceres::Solver::Summary summary;
    ceres::Solve(solver_options, &problem, &summary);
    if (round == 0) result.summary.initial_cost = summary.initial_cost;
    result.summary.final_cost = summary.final_cost;
    result.summary.iterations += static_cast<int>(summary.iterations.size());

    for (std::size_t p = 0; p < points.size(); ++p) {
      for (const PointTrack::Observation& o : points[p].observations) {
        const double chi2 = geometry::SquaredReprojectionError(
            camera, poses[o.keyframe].ToTransform(), points[p].position, o.u, o.v, o.u_right,
            options.sigma);
        if (!(chi2 <
              (o.u_right >= 0 ? geometry::kChiSquare95ThreeDof : geometry::kChiSquare95TwoDof))) {
          rejected.insert({p, o.keyframe});
        }
      }
    }
  }
  for (const std::int64_t id : moving) {
    result.T_map_camera[id] = poses[id].ToTransform().inverse();
  }
  result.summary.keyframes = moving.size();
  result.summary.points = points.size();
  result.summary.rejected_observations = rejected.size();
  return result;
}

}  // namespace stereo_fabmap_slam::backend
