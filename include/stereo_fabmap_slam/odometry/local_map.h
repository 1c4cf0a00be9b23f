#pragma once

#include <cstdint>
#include <deque>
#include <map>
#include <vector>

#include <Eigen/Geometry>
#include <opencv2/core.hpp>

#include "stereo_fabmap_slam/map/keyframe.h"
#include "stereo_fabmap_slam/map/keyframe_update.h"

namespace stereo_fabmap_slam::odometry {

struct MapPoint {
  std::int64_t id = 0;
  Eigen::Vector3d position = Eigen::Vector3d::Zero();  // world frame
  cv::Mat descriptor;  // from the most recent keyframe that saw it: closest in viewpoint
  int keyframes = 0;   // local keyframes observing it
};

// The tracker's view of the map: the last few keyframes and the points they see, kept in step
// with the backend's optimisation through ApplyUpdate().
class LocalMap {
 public:
  explicit LocalMap(int max_keyframes) : max_keyframes_(max_keyframes) {}

  // Adds a keyframe (creating its new points) and drops the oldest beyond max_keyframes.
  void AddKeyframe(const map::Keyframe& keyframe);
  void ApplyUpdate(const map::KeyframeUpdate& update);
  void Clear();

  const std::map<std::int64_t, MapPoint>& points() const { return points_; }
  bool empty() const { return keyframes_.empty(); }
  // Latest pose of a local keyframe; nullptr if it is no longer local.
  const Eigen::Isometry3d* KeyframePose(std::int64_t id) const;
  std::int64_t last_keyframe_id() const { return keyframes_.back().id; }

 private:
  struct LocalKeyframe {
    std::int64_t id;
    Eigen::Isometry3d T_world_camera;
    std::vector<std::int64_t> point_ids;
  };

  int max_keyframes_;
  std::deque<LocalKeyframe> keyframes_;
  std::map<std::int64_t, MapPoint> points_;
};

}  // namespace stereo_fabmap_slam::odometry
