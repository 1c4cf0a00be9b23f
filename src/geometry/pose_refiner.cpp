#include "stereo_fabmap_slam/geometry/pose_refiner.h"

#include <cmath>
#include <memory>
#include <stdexcept>

#include <ceres/ceres.h>

#include "stereo_fabmap_slam/geometry/chi_square.h"
#include "stereo_fabmap_slam/geometry/pose_parameters.h"
#include "stereo_fabmap_slam/geometry/reprojection_error.h"

namespace stereo_fabmap_slam::geometry {

void PoseRefinementOptions::Visit(io::OptionVisitor& visitor) {
  visitor.Visit("sigma", &sigma);
  visitor.Visit("rounds", &rounds);
  visitor.Visit("iterations", &iterations);
}

void PoseRefinementOptions::Validate() const {
  if (!(sigma > 0)) throw std::invalid_argument("pose refinement sigma must be > 0");
  if (rounds < 1 || iterations < 1) {
    throw std::invalid_argument("pose refinement rounds and iterations must be >= 1");
  }
}

PointMatches MatchedPoints(const std::vector<cv::KeyPoint>& keypoints,
                           const std::vector<float>& u_right,
                           const std::vector<Eigen::Vector3d>& frame_points,
                           const std::vector<Eigen::Vector3d>& points,
                           const std::vector<cv::DMatch>& matches) {
  PointMatches matched;
  matched.correspondences.reserve(matches.size());
  matched.observations.reserve(matches.size());
  for (const cv::DMatch& match : matches) {
    const std::size_t i = static_cast<std::size_t>(match.queryIdx);
    const Eigen::Vector3d& point = points[static_cast<std::size_t>(match.trainIdx)];
    const cv::Point2f& pixel = keypoints[i].pt;
    matched.correspondences.push_back(
        {point, Eigen::Vector2d(pixel.x, pixel.y), u_right[i] >= 0.0f, frame_points[i]});
    matched.observations.push_back({point, pixel.x, pixel.y, u_right[i]});
  }
  return matched;
}

PoseRefinement RefinePose(const std::vector<PoseObservation>& observations,
                          const StereoCamera& camera, const Eigen::Isometry3d& initial,
                          const PoseRefinementOptions& options,
                          const std::vector<bool>* initial_inliers) {
  PoseRefinement result;
  result.T_camera_world = initial;
  result.inlier =
      initial_inliers != nullptr ? *initial_inliers : std::vector<bool>(observations.size(), true);
  ceres::HuberLoss loss(std::sqrt(kChiSquare95ThreeDof));
  // One array of costs for every round's problem, not one allocation per residual.
  const auto costs = std::make_unique<FixedPointReprojectionCost[]>(observations.size());
  for (int round = 0; round < options.rounds; ++round) {
    PoseParameters pose = PoseParameters::FromTransform(result.T_camera_world);
    ceres::Problem::Options problem_options;
    problem_options.loss_function_ownership = ceres::DO_NOT_TAKE_OWNERSHIP;
    problem_options.cost_function_ownership = ceres::DO_NOT_TAKE_OWNERSHIP;
    ceres::Problem problem(problem_options);
    int residual_blocks = 0;
    for (std::size_t i = 0; i < observations.size(); ++i) {
      if (!result.inlier[i]) continue;
      const PoseObservation& o = observations[i];
      FixedPointReprojectionCost& cost = costs[static_cast<std::size_t>(residual_blocks++)];
      cost.Set(camera, o.world, o.u, o.v, o.u_right, options.sigma);
      problem.AddResidualBlock(&cost, &loss, pose.rotation, pose.translation);
    }
    if (residual_blocks < 3) break;
    problem.SetManifold(pose.rotation, new ceres::EigenQuaternionManifold);
    ceres::Solver::Options solver_options;
    // Six unknowns: the normal equations are a 6x6 system, far cheaper than a QR of J.
    solver_options.linear_solver_type = ceres::DENSE_NORMAL_CHOLESKY;
    solver_options.max_num_iterations = options.iterations;
    solver_options.num_threads = 1;
    solver_options.logging_type = ceres::SILENT;
    ceres::Solver::Summary summary;
    ceres::Solve(solver_options, &problem, &summary);
    result.T_camera_world = pose.ToTransform();

    result.inliers = 0;
    bool changed = false;
    for (std::size_t i = 0; i < observations.size(); ++i) {
      const PoseObservation& o = observations[i];
      const double chi2 = SquaredReprojectionError(camera, result.T_camera_world, o.world, o.u, o.v,
                                                   o.u_right, options.sigma);
      const bool inlier = chi2 < (o.u_right >= 0 ? kChiSquare95ThreeDof : kChiSquare95TwoDof);
      changed |= inlier != result.inlier[i];
      result.inlier[i] = inlier;
      result.inliers += inlier ? 1 : 0;
    }
    // The same inliers again: another round would solve the same problem from its optimum.
    if (!changed) break;
  }
  std::vector<ObservedPoint> inlier_points;
  inlier_points.reserve(static_cast<std::size_t>(result.inliers));
  for (std::size_t i = 0; i < observations.size(); ++i) {
    if (!result.inlier[i]) continue;
    inlier_points.push_back(
        {result.T_camera_world * observations[i].world, observations[i].u_right >= 0});
  }
  result.covariance = StereoPoseCovariance(camera, inlier_points, options.sigma);
  return result;
}

}  // namespace stereo_fabmap_slam::geometry
