#pragma once

#include <cstdint>
#include <vector>

#include <Eigen/Geometry>
#include <opencv2/core.hpp>

#include "stereo_fabmap_slam/features/stereo_features.h"

namespace stereo_fabmap_slam::map {

// What the tracker hands to its consumers when it makes a keyframe (the content of
// msg/Keyframe.msg): everything the backend and place recognition need, nothing shared.
struct Keyframe {
  std::int64_t id = 0;
  double timestamp = 0;  // [s]
  // Pose in the odometry frame, as tracked (REP-105 odom: continuous, never corrected by loops).
  Eigen::Isometry3d T_world_camera = Eigen::Isometry3d::Identity();
  features::StereoFeatures features;
  // Map point observed by each key point; -1 if none. Ids the backend has not seen before are
  // new points, placed at T_world_camera * features.points[i].
  std::vector<std::int64_t> map_point_ids;
  // Tracking was lost (or reset) before this keyframe: it starts a new segment, joined to no
  // earlier keyframe by odometry.
  bool starts_new_segment = false;
  // Place recognition's descriptors of the left image (its own key point selection, the
  // vocabulary's descriptor type: CV_8U binary or CV_32F), one per row; computed once by the
  // front end so that loop detection needs nothing but the keyframe.
  cv::Mat place_descriptors;
};

}  // namespace stereo_fabmap_slam::map
