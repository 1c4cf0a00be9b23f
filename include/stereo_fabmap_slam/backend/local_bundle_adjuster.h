#pragma once

#include <cstdint>
#include <deque>
#include <functional>
#include <map>
#include <memory>
#include <set>
#include <unordered_map>
#include <utility>
#include <vector>

#include <Eigen/Geometry>

#include "stereo_fabmap_slam/backend/backend_options.h"
#include "stereo_fabmap_slam/backend/point_observation.h"
#include "stereo_fabmap_slam/geometry/pose_parameters.h"
#include "stereo_fabmap_slam/geometry/reprojection_error.h"
#include "stereo_fabmap_slam/geometry/stereo_camera.h"
#include "stereo_fabmap_slam/io/option_reader.h"
#include "stereo_fabmap_slam/map/keyframe.h"
#include "stereo_fabmap_slam/map/keyframe_update.h"

namespace stereo_fabmap_slam::backend {

// Windowed bundle adjustment with Ceres: the last `window` keyframes and the points they see,
// stereo reprojection residuals (u_left, v, u_right) with a Huber loss; the oldest keyframes of
// the window, and older keyframes that see the same points, stay fixed. Points seen by a single
// keyframe are left out (they cannot inform a pose) and re-placed from their keyframe's new pose,
// which is their exact optimum. Observations failing a 95 % chi-square test after a round are
// removed; points left with none are removed.
// Keeps every keyframe (pose and observations), so its memory grows with keyframes only.
class LocalBundleAdjuster {
 public:
  using Observation = PointObservation;

  LocalBundleAdjuster(const BundleAdjustmentOptions& options, const geometry::StereoCamera& camera);

  // Adds a keyframe and optimises the window; returns what changed. With optimise = false the
  // keyframe only joins the map and the window (a caller that falls behind optimises once for
  // several keyframes); the update is then empty.
  map::KeyframeUpdate AddKeyframe(const map::Keyframe& keyframe, bool optimise = true);

  // Latest pose (T_world_camera) of every keyframe so far, by id.
  std::map<std::int64_t, Eigen::Isometry3d> KeyframePoses() const;

  // Every point kept, with its id, position (odom frame) and observations: what a refinement of
  // the whole map needs.
  void ForEachPoint(const std::function<void(std::int64_t, const Eigen::Vector3d&,
                                             const std::vector<Observation>&)>& visit) const;

 private:
  struct Point {
    Eigen::Vector3d position;
    std::vector<Observation> observations;
    // Where the point was measured first: that keyframe and the stereo point in its frame. A
    // point seen once follows its keyframe exactly, which is the optimum for it.
    std::int64_t anchor_keyframe;
    Eigen::Vector3d anchor_point;
  };
  struct Keyframe {
    Eigen::Isometry3d T_world_camera;
    std::vector<std::int64_t> points;
  };

  map::KeyframeUpdate Optimise();
  // The covariance of each step between consecutive keyframes of the window (the later one free)
  // at the optimum just found (WindowCovariance), into update->step_covariances.
  void StepCovariances(const std::vector<std::int64_t>& point_ids,
                       const std::map<std::int64_t, geometry::PoseParameters>& poses,
                       const std::set<std::int64_t>& free_keyframes,
                       const std::set<std::pair<std::int64_t, std::int64_t>>& rejected,
                       map::KeyframeUpdate* update) const;

  BundleAdjustmentOptions options_;
  geometry::StereoCamera camera_;
  std::map<std::int64_t, Keyframe> keyframes_;
  std::unordered_map<std::int64_t, Point> points_;
  std::deque<std::int64_t> window_;
  // The residuals' costs, reused by every problem (each lives for one solve): no allocation per
  // residual; they lie in memory in the order the residuals are added, point by point.
  std::unique_ptr<geometry::ReprojectionCost[]> costs_;
  std::size_t costs_capacity_ = 0;
};

}  // namespace stereo_fabmap_slam::backend
