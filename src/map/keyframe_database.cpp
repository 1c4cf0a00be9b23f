#include "stereo_fabmap_slam/map/keyframe_database.h"

#include <stdexcept>
#include <string>

namespace stereo_fabmap_slam::map {

const StoredKeyframe& KeyframeDatabase::Add(Keyframe keyframe, std::vector<int> words) {
  if (!keyframes_.empty() && keyframe.id <= keyframes_.rbegin()->first) {
    throw std::invalid_argument("keyframe " + std::to_string(keyframe.id) +
                                " is not newer than the map's last keyframe " +
                                std::to_string(keyframes_.rbegin()->first));
  }
  StoredKeyframe stored;
  if (keyframes_.empty() || keyframe.starts_new_segment) {
    ++segment_;
  } else {
    const StoredKeyframe& previous = keyframes_.rbegin()->second;
    stored.path_length = previous.path_length + (keyframe.T_world_camera.translation() -
                                                 previous.keyframe.T_world_camera.translation())
                                                    .norm();
  }
  stored.segment = segment_;
  keyframe.place_descriptors = cv::Mat();
  stored.keyframe = std::move(keyframe);
  stored.words = std::move(words);
  return keyframes_.emplace(stored.keyframe.id, std::move(stored)).first->second;
}

void KeyframeDatabase::UpdatePose(std::int64_t id, const Eigen::Isometry3d& T_odom_camera) {
  const auto it = keyframes_.find(id);
  if (it != keyframes_.end()) it->second.keyframe.T_world_camera = T_odom_camera;
}

}  // namespace stereo_fabmap_slam::map
