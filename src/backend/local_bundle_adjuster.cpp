#include "stereo_fabmap_slam/backend/local_bundle_adjuster.h"

#include <algorithm>
#include <cmath>
#include <memory>
#include <set>
#include <stdexcept>

#include <ceres/ceres.h>

#include "stereo_fabmap_slam/backend/window_covariance.h"
#include "stereo_fabmap_slam/geometry/chi_square.h"
#include "stereo_fabmap_slam/geometry/pose_parameters.h"
#include "stereo_fabmap_slam/geometry/reprojection_error.h"
#include "stereo_fabmap_slam/geometry/small_step_stop.h"

namespace stereo_fabmap_slam::backend {

LocalBundleAdjuster::LocalBundleAdjuster(const BundleAdjustmentOptions& options,
                                         const geometry::StereoCamera& camera)
    : options_((options.Validate(), options)), camera_(camera) {}

map::KeyframeUpdate LocalBundleAdjuster::AddKeyframe(const map::Keyframe& data, bool optimise) {
  if (data.starts_new_segment) window_.clear();  // the old map is unrelated: no shared gauge
  Keyframe& keyframe = keyframes_[data.id];
  keyframe.T_world_camera = data.T_world_camera;
  for (std::size_t i = 0; i < data.map_point_ids.size(); ++i) {
    const std::int64_t id = data.map_point_ids[i];
    if (id < 0) continue;
    auto [it, inserted] = points_.try_emplace(id);
    if (inserted) {
      it->second.position = data.T_world_camera * data.features.points[i];
      it->second.anchor_keyframe = data.id;
      it->second.anchor_point = data.features.points[i];
    }
    const cv::Point2f& p = data.features.keypoints[i].pt;
    it->second.observations.push_back({data.id, p.x, p.y, data.features.u_right[i]});
    keyframe.points.push_back(id);
  }
  window_.push_back(data.id);
  while (static_cast<int>(window_.size()) > options_.window) window_.pop_front();
  return optimise ? Optimise() : map::KeyframeUpdate();
}

map::KeyframeUpdate LocalBundleAdjuster::Optimise() {
  map::KeyframeUpdate update;
  // Free keyframes: the window without its oldest. Points: those the window sees.
  const std::set<std::int64_t> window(window_.begin(), window_.end());
  std::set<std::int64_t> free_keyframes(
      std::next(window_.begin(),
                std::min<std::ptrdiff_t>(options_.fixed_keyframes, window_.size())),
      window_.end());
  // A point seen by one keyframe only can absorb its own residual exactly: it says nothing about
  // poses, so it stays out of the problem (about half the points, seen once so far). In order of
  // id, as the residuals are added; a sorted vector, not a set: ~4,000 insertions a keyframe.
  std::vector<std::int64_t> point_ids;
  for (const std::int64_t id : window_) {
    for (const std::int64_t p : keyframes_[id].points) {
      const auto it = points_.find(p);
      if (it != points_.end() && it->second.observations.size() >= 2) point_ids.push_back(p);
    }
  }
  std::sort(point_ids.begin(), point_ids.end());
  point_ids.erase(std::unique(point_ids.begin(), point_ids.end()), point_ids.end());
  if (free_keyframes.empty() && point_ids.empty()) return update;

  std::map<std::int64_t, geometry::PoseParameters> poses;
  for (const std::int64_t p : point_ids) {
    for (const Observation& o : points_[p].observations) {
      if (!poses.count(o.keyframe)) {
        poses[o.keyframe] = geometry::PoseParameters::FromTransform(
            keyframes_[o.keyframe].T_world_camera.inverse());
      }
    }
  }

  ceres::HuberLoss loss(std::sqrt(geometry::kChiSquare95ThreeDof));
  std::set<std::pair<std::int64_t, std::int64_t>> rejected;  // (point, keyframe)
  for (int round = 0; round < options_.rounds; ++round) {
    std::size_t residuals = 0;
    for (const std::int64_t p : point_ids) residuals += points_[p].observations.size();
    if (residuals > costs_capacity_) {
      costs_capacity_ = residuals + residuals / 2;
      costs_ = std::make_unique<geometry::ReprojectionCost[]>(costs_capacity_);
    }
    ceres::Problem::Options problem_options;
    problem_options.loss_function_ownership = ceres::DO_NOT_TAKE_OWNERSHIP;
    problem_options.cost_function_ownership = ceres::DO_NOT_TAKE_OWNERSHIP;
    // What Ceres' checks of each added residual look for cannot happen here: every block is an
    // array of its own (a pose's two in `poses`, a point's position in points_), of the size
    // the cost function declares. Unchecked, building the problem of ~8,000 residuals took 2.6
    // instead of 3.2 ms a keyframe (the 4-lap route, one pair of instrumented runs).
    problem_options.disable_all_safety_checks = true;
    ceres::Problem problem(problem_options);
    std::size_t next_cost = 0;
    for (const std::int64_t p : point_ids) {
      Point& point = points_[p];
      for (const Observation& o : point.observations) {
        if (rejected.count({p, o.keyframe})) continue;
        geometry::PoseParameters& pose = poses[o.keyframe];
        geometry::ReprojectionCost& cost = costs_[next_cost++];
        cost.Set(camera_, o.u, o.v, o.u_right, options_.sigma);
        problem.AddResidualBlock(&cost, &loss, pose.rotation, pose.translation,
                                 point.position.data());
      }
    }
    for (auto& [id, pose] : poses) {
      if (!problem.HasParameterBlock(pose.rotation)) continue;
      problem.SetManifold(pose.rotation, new ceres::EigenQuaternionManifold);
      if (!free_keyframes.count(id)) {
        problem.SetParameterBlockConstant(pose.rotation);
        problem.SetParameterBlockConstant(pose.translation);
      }
    }
    ceres::Solver::Options solver_options;
    // A window of ~10 cameras makes a small, dense reduced camera system.
    solver_options.linear_solver_type = ceres::DENSE_SCHUR;
    solver_options.max_num_iterations = options_.iterations;
    solver_options.num_threads = options_.threads;
    solver_options.logging_type = ceres::SILENT;
    // The elimination order is known, points first, then poses: given, it spares Ceres the
    // search for an independent set in every solve (4.6 -> 2.3 ms of preprocessing).
    auto ordering = std::make_shared<ceres::ParameterBlockOrdering>();
    for (const std::int64_t p : point_ids) {
      ordering->AddElementToGroup(points_[p].position.data(), 0);
    }
    for (auto& [id, pose] : poses) {
      if (!problem.HasParameterBlock(pose.rotation)) continue;
      ordering->AddElementToGroup(pose.rotation, 1);
      ordering->AddElementToGroup(pose.translation, 1);
    }
    solver_options.linear_solver_ordering = ordering;
    geometry::SmallStepStop small_step_stop(options_.converged_step_decrease);
    if (options_.converged_step_decrease > 0) solver_options.callbacks.push_back(&small_step_stop);
    ceres::Solver::Summary summary;
    ceres::Solve(solver_options, &problem, &summary);

    const std::size_t rejected_before = rejected.size();
    std::map<std::int64_t, Eigen::Isometry3d> T_camera_world;
    for (const auto& [id, pose] : poses) T_camera_world.emplace(id, pose.ToTransform());
    for (const std::int64_t p : point_ids) {
      const Point& point = points_[p];
      for (const Observation& o : point.observations) {
        const double chi2 =
            geometry::SquaredReprojectionError(camera_, T_camera_world.at(o.keyframe),
                                               point.position, o.u, o.v, o.u_right, options_.sigma);
        if (!(chi2 <
              (o.u_right >= 0 ? geometry::kChiSquare95ThreeDof : geometry::kChiSquare95TwoDof))) {
          rejected.insert({p, o.keyframe});
        }
      }
    }
    // Nothing new left out: another round would solve the same problem from its optimum.
    if (rejected.size() == rejected_before) break;
  }

  if (options_.step_covariances)
    StepCovariances(point_ids, poses, free_keyframes, rejected, &update);
  for (const std::int64_t id : free_keyframes) {
    keyframes_[id].T_world_camera = poses[id].ToTransform().inverse();
    update.keyframe_poses.emplace_back(id, keyframes_[id].T_world_camera);
    for (const std::int64_t p : keyframes_[id].points) {
      const auto it = points_.find(p);
      if (it == points_.end() || it->second.observations.size() != 1 ||
          it->second.anchor_keyframe != id) {
        continue;
      }
      it->second.position = keyframes_[id].T_world_camera * it->second.anchor_point;
      update.point_positions.emplace_back(p, it->second.position);
    }
  }
  // Drop rejected observations; a point without observations goes.
  for (const std::int64_t p : point_ids) {
    Point& point = points_[p];
    point.observations.erase(std::remove_if(point.observations.begin(), point.observations.end(),
                                            [&](const Observation& o) {
                                              return rejected.count({p, o.keyframe}) > 0;
                                            }),
                             point.observations.end());
    if (point.observations.empty()) {
      points_.erase(p);
      update.removed_points.push_back(p);
    } else {
      update.point_positions.emplace_back(p, point.position);
    }
  }
  return update;
}

void LocalBundleAdjuster::StepCovariances(
    const std::vector<std::int64_t>& point_ids,
    const std::map<std::int64_t, geometry::PoseParameters>& poses,
    const std::set<std::int64_t>& free_keyframes,
    const std::set<std::pair<std::int64_t, std::int64_t>>& rejected,
    map::KeyframeUpdate* update) const {
  WindowCovariance covariance(camera_, options_.sigma, std::sqrt(geometry::kChiSquare95ThreeDof));
  std::map<std::int64_t, int> index;
  for (const auto& [id, pose] : poses) {
    index[id] = covariance.AddPose(pose.ToTransform().inverse(), free_keyframes.count(id) > 0);
  }
  std::vector<WindowCovariance::Observation> observations;
  for (const std::int64_t p : point_ids) {
    const Point& point = points_.at(p);
    observations.clear();
    for (const Observation& o : point.observations) {
      if (!rejected.count({p, o.keyframe})) {
        observations.push_back({index.at(o.keyframe), o.u, o.v, o.u_right});
      }
    }
    if (observations.size() >= 2) covariance.AddPoint(point.position, observations);
  }
  if (!covariance.Compute()) return;
  for (std::size_t i = 1; i < window_.size(); ++i) {
    const std::int64_t from = window_[i - 1], to = window_[i];
    if (!free_keyframes.count(to) || !index.count(from) || !index.count(to)) continue;
    update->step_covariances.push_back(
        {from, to, covariance.RelativeCovariance(index.at(from), index.at(to))});
  }
}

std::map<std::int64_t, Eigen::Isometry3d> LocalBundleAdjuster::KeyframePoses() const {
  std::map<std::int64_t, Eigen::Isometry3d> poses;
  for (const auto& [id, keyframe] : keyframes_) poses[id] = keyframe.T_world_camera;
  return poses;
}

void LocalBundleAdjuster::ForEachPoint(
    const std::function<void(std::int64_t, const Eigen::Vector3d&,
                             const std::vector<Observation>&)>& visit) const {
  for (const auto& [id, point] : points_) visit(id, point.position, point.observations);
}

}  // namespace stereo_fabmap_slam::backend
