#pragma once

#include <cstdint>
#include <utility>
#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>

namespace stereo_fabmap_slam::map {

// A verified revisit: the query keyframe was recognised as a view of the match keyframe, and
// geometric verification measured where the query camera is relative to the match's.
struct LoopEdge {
  std::int64_t query_id = -1;
  std::int64_t match_id = -1;
  // Pose of the query keyframe's camera in the match keyframe's camera frame.
  Eigen::Isometry3d T_match_query = Eigen::Isometry3d::Identity();
  // Inverse covariance of the relative pose, in the order (translation x y z, rotation x y z as
  // a small-angle vector) of the pose graph's residual.
  Eigen::Matrix<double, 6, 6> information = Eigen::Matrix<double, 6, 6>::Identity();
  int inliers = 0;  // verified 2-D/3-D matches
  // The inliers whose key points are map points in both keyframes: (the query's map point, the
  // match's), the same place seen on both passes (a refinement of the whole map fuses them).
  std::vector<std::pair<std::int64_t, std::int64_t>> shared_points;
  double probability = 0;  // FAB-MAP's posterior of the match place
};

}  // namespace stereo_fabmap_slam::map
