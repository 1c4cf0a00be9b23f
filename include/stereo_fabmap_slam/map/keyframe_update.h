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
};

}  // namespace stereo_fabmap_slam::map
