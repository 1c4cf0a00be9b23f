#pragma once

#include <cstdint>
#include <utility>
#include <vector>

#include <Eigen/Geometry>

namespace stereo_fabmap_slam::map {

// What the bundle adjustment sends back after optimising: new keyframe poses and point
// positions (odometry frame), and the points it removed as outliers.
struct KeyframeUpdate {
  std::vector<std::pair<std::int64_t, Eigen::Isometry3d>> keyframe_poses;  // T_world_camera
  std::vector<std::pair<std::int64_t, Eigen::Vector3d>> point_positions;
  std::vector<std::int64_t> removed_points;
  // With BundleAdjustmentOptions::step_covariances: the covariance of the step from keyframe
  // `from` to the next keyframe of the window, `to` (T_from^-1 * T_to, right perturbation,
  // translation then rotation), at the poses above.
  struct StepCovariance {
    std::int64_t from, to;
    Eigen::Matrix<double, 6, 6> covariance;
  };
  std::vector<StepCovariance> step_covariances;
};

}  // namespace stereo_fabmap_slam::map
