#pragma once

#include <cstddef>
#include <cstdint>
#include <map>
#include <vector>

#include <Eigen/Geometry>

#include "stereo_fabmap_slam/backend/local_bundle_adjuster.h"
#include "stereo_fabmap_slam/backend/pose_graph.h"
#include "stereo_fabmap_slam/geometry/stereo_camera.h"

namespace stereo_fabmap_slam::backend {

// A keyframe of the refinement: where the pose graph puts it (map) and where the odometry has
// it (odom, the frame of the points' tracks).
struct RefinementKeyframe {
  Eigen::Isometry3d T_map_camera = Eigen::Isometry3d::Identity();
  Eigen::Isometry3d T_odom_camera = Eigen::Isometry3d::Identity();
  bool fixed = false;  // the gauge, or a keyframe the refinement must not move
};

struct RefinementSummary {
  std::size_t keyframes = 0;  // moved
  std::size_t points = 0;
  std::size_t observations = 0;
  std::size_t rejected_observations = 0;  // outside the 95 % chi-square after the first round
  int iterations = 0;
  double initial_cost = 0;
  double final_cost = 0;
};

struct RefinementResult {
  std::map<std::int64_t, Eigen::Isometry3d> T_map_camera;  // every keyframe that moved
  RefinementSummary summary;
};

// Bundle adjustment of a map after loop closing: the keyframes' map poses and the points they
// share, refined together with the loop and relocalization edges. The pose graph corrects a
// loop's drift with one fixed uncertainty per odometry edge, however well the edge's points
// constrained it; here the points themselves weigh every step (a corridor seen by 300 points
// bends less than a turn seen by 40), and the loop edges hold the revisits together.
// Each point starts where its first observing keyframe's correction (map pose * odom pose^-1)
// puts it, so the problem starts at the pose graph's solution. Residuals: stereo reprojection
// with a Huber loss as in the windowed bundle adjustment; loop edges as in the pose graph (a
// Cauchy loss). A keyframe with fewer than `min_observations` observations stays where it is
// (nothing would hold it). Stateless; no clock.
class MapRefinement {
 public:
  struct Options {
    int iterations = 10;
    int rounds = 2;      // optimise, drop observations outside the 95 % chi-square, again
    double sigma = 1.0;  // [px] key point noise, as the windowed bundle adjustment's
    double loop_loss_scale = 3.5;
    int min_observations = 10;
    int threads = 1;
  };

  static RefinementResult Refine(const Options& options, const geometry::StereoCamera& camera,
                                 const std::map<std::int64_t, RefinementKeyframe>& keyframes,
                                 const std::vector<PointTrack>& tracks,
                                 const std::vector<PoseGraphEdge>& loop_edges);
};

}  // namespace stereo_fabmap_slam::backend
