#pragma once

#include <cstdint>
#include <map>
#include <vector>

#include <Eigen/Geometry>

#include "stereo_fabmap_slam/map/keyframe.h"

namespace stereo_fabmap_slam::map {

// One keyframe as the map keeps it: its features and stereo points (for geometric verification
// and relocalization), its place-recognition words, and where it lies on the odometry's path.
struct StoredKeyframe {
  Keyframe keyframe;  // pose in odom, kept current with the bundle adjustment
  std::vector<int> words;
  int segment = 0;         // odometry segment: a new one starts after tracking was lost
  double path_length = 0;  // [m] travelled along the segment's keyframes up to this one
};

// Every keyframe of the map, by id: one store for loop detection and relocalization.
class KeyframeDatabase {
 public:
  // Adds a keyframe (its place descriptors are not kept: `words` replace them). Ids must be new
  // and increasing; std::invalid_argument otherwise.
  const StoredKeyframe& Add(Keyframe keyframe, std::vector<int> words);
  // The bundle adjustment moved a keyframe in odom; unknown ids are ignored (not stored yet).
  void UpdatePose(std::int64_t id, const Eigen::Isometry3d& T_odom_camera);

  bool Contains(std::int64_t id) const { return keyframes_.count(id) > 0; }
  // Throws std::out_of_range for an unknown id.
  const StoredKeyframe& Get(std::int64_t id) const { return keyframes_.at(id); }
  std::size_t size() const { return keyframes_.size(); }
  bool empty() const { return keyframes_.empty(); }
  const std::map<std::int64_t, StoredKeyframe>& keyframes() const { return keyframes_; }

 private:
  std::map<std::int64_t, StoredKeyframe> keyframes_;
  int segment_ = -1;
};

}  // namespace stereo_fabmap_slam::map
