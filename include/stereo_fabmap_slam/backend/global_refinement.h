#pragma once

#include <cstdint>
#include <map>
#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "stereo_fabmap_slam/backend/backend_options.h"
#include "stereo_fabmap_slam/backend/point_observation.h"
#include "stereo_fabmap_slam/backend/pose_graph.h"
#include "stereo_fabmap_slam/geometry/stereo_camera.h"

namespace stereo_fabmap_slam::backend {

struct GlobalRefinementSummary {
  bool converged = false;
  int iterations = 0;
  std::size_t keyframes = 0;  // poses optimised (the fixed ones not counted)
  std::size_t points = 0;
  std::size_t observations = 0;
  std::size_t edges = 0;  // pose graph edges in the problem
  double initial_cost = 0, final_cost = 0;
};

// Bundle adjustment of the whole map in the map frame, after loop closing has put its keyframes
// where the pose graph's edges agree: the keyframes' poses and the points they saw, refined
// together against the points' stereo reprojections, as ORB-SLAM's global bundle adjustment does.
// The pose graph summarises each step between keyframes by one relative pose with a fixed
// uncertainty; here the steps are what the points say they are, so a step measured on many
// points is stiff and one measured on few gives way. Points join only keyframes that saw them
// (across a loop only where the caller fused a loop's shared points into one point), so the
// graph's other edges join the problem too: loops and
// relocalizations (with the pose graph's Cauchy loss: a wrong one that survived far off barely
// pulls), and the odometry edges of steps that share too few points to hold them (a tracking
// loss's gap shares none). The keyframes marked fixed are the gauge.
// Not thread-safe; no clock, no global state.
class GlobalRefinement {
 public:
  using Observation = PointObservation;

  GlobalRefinement(const GlobalRefinementOptions& options, const PoseGraphOptions& graph_options,
                   const geometry::StereoCamera& camera, double sigma);

  void AddKeyframe(std::int64_t id, const Eigen::Isometry3d& T_map_camera, bool fixed);
  // A point (map frame) and its observations; those of keyframes not added are ignored, and a
  // point left with fewer than two is left out (it says nothing about the poses).
  void AddPoint(const Eigen::Vector3d& point_map, const std::vector<Observation>& observations);
  // A pose graph edge between two added keyframes (others are ignored).
  void AddEdge(const PoseGraphEdge& edge);

  GlobalRefinementSummary Solve();
  // T_map_camera of every added keyframe (refined after Solve()).
  std::map<std::int64_t, Eigen::Isometry3d> Poses() const;

 private:
  struct Pose {
    double rotation[4];  // T_camera_map as an Eigen quaternion (x, y, z, w)
    double translation[3];
    bool fixed;

    Eigen::Isometry3d CameraFromMap() const;  // T_camera_map
  };
  struct Point {
    Eigen::Vector3d position;
    std::vector<Observation> observations;
  };

  // The odometry edges of steps whose keyframes share options_.odometry_edge_below_shared_points
  // points or more leave the problem.
  void DropOdometryEdgesThePointsHold();

  GlobalRefinementOptions options_;
  PoseGraphOptions graph_options_;
  geometry::StereoCamera camera_;
  double sigma_;
  std::map<std::int64_t, Pose> poses_;
  std::vector<Point> points_;
  std::vector<PoseGraphEdge> edges_;
};

}  // namespace stereo_fabmap_slam::backend
