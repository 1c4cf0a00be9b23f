#pragma once

#include <cstdint>
#include <utility>
#include <vector>

#include <Eigen/Geometry>

#include "stereo_fabmap_slam/features/stereo_features.h"

namespace stereo_fabmap_slam::odometry {

// What the tracker hands to its consumers when it makes a keyframe (the content of
// msg/Keyframe.msg): everything the backend and place recognition need, nothing shared.
struct KeyframeData {
  std::int64_t id = 0;
  double timestamp = 0;  // [s]
  Eigen::Isometry3d T_world_camera = Eigen::Isometry3d::Identity();
  features::StereoFeatures features;
  // Map point observed by each key point; -1 if none. Ids the backend has not seen before are
  // new points, placed at T_world_camera * features.points[i].
  std::vector<std::int64_t> map_point_ids;
  // Tracking was lost before this keyframe: it starts a new map, unrelated to earlier keyframes.
  bool starts_new_map = false;
};

// What the backend sends back after optimising: new keyframe poses and point positions, and the
// points it removed as outliers.
struct KeyframeUpdate {
  std::vector<std::pair<std::int64_t, Eigen::Isometry3d>> keyframe_poses;  // T_world_camera
  std::vector<std::pair<std::int64_t, Eigen::Vector3d>> point_positions;
  std::vector<std::int64_t> removed_points;
};

}  // namespace stereo_fabmap_slam::odometry
