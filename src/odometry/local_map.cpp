#include "stereo_fabmap_slam/odometry/local_map.h"

namespace stereo_fabmap_slam::odometry {

void LocalMap::AddKeyframe(const map::Keyframe& keyframe) {
  LocalKeyframe local{keyframe.id, keyframe.T_world_camera, {}};
  for (std::size_t i = 0; i < keyframe.map_point_ids.size(); ++i) {
    const std::int64_t id = keyframe.map_point_ids[i];
    if (id < 0) continue;
    auto [it, inserted] = points_.try_emplace(id);
    MapPoint& point = it->second;
    if (inserted) {
      point.id = id;
      point.position = keyframe.T_world_camera * keyframe.features.points[i];
    }
    point.descriptor = keyframe.features.descriptors.row(static_cast<int>(i));
    ++point.keyframes;
    local.point_ids.push_back(id);
  }
  keyframes_.push_back(std::move(local));
  while (static_cast<int>(keyframes_.size()) > max_keyframes_) {
    for (const std::int64_t id : keyframes_.front().point_ids) {
      const auto it = points_.find(id);
      if (it != points_.end() && --it->second.keyframes <= 0) points_.erase(it);
    }
    keyframes_.pop_front();
  }
}

void LocalMap::ApplyUpdate(const map::KeyframeUpdate& update) {
  for (const auto& [id, pose] : update.keyframe_poses) {
    for (LocalKeyframe& keyframe : keyframes_) {
      if (keyframe.id == id) keyframe.T_world_camera = pose;
    }
  }
  for (const auto& [id, position] : update.point_positions) {
    const auto it = points_.find(id);
    if (it != points_.end()) it->second.position = position;
  }
  for (const std::int64_t id : update.removed_points) points_.erase(id);
}

void LocalMap::Clear() {
  keyframes_.clear();
  points_.clear();
}

const Eigen::Isometry3d* LocalMap::KeyframePose(std::int64_t id) const {
  for (const LocalKeyframe& keyframe : keyframes_) {
    if (keyframe.id == id) return &keyframe.T_world_camera;
  }
  return nullptr;
}

}  // namespace stereo_fabmap_slam::odometry
