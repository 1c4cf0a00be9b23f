#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include <Eigen/Geometry>

#include "stereo_fabmap_slam/geometry/stereo_camera.h"
#include "stereo_fabmap_slam/map/keyframe.h"
#include "stereo_fabmap_slam/map/loop_edge.h"

namespace stereo_fabmap_slam::map {

// One keyframe of a saved map: the keyframe as the odometry made it (pose in odom after bundle
// adjustment, features, stereo points, map point ids; no place descriptors), its place words and
// its optimised pose in map.
struct SavedKeyframe {
  Keyframe keyframe;
  std::vector<int> words;
  Eigen::Isometry3d T_map_camera = Eigen::Isometry3d::Identity();
};

struct SavedEdge {
  LoopEdge edge;
  bool relocalization = false;  // else a loop
};

// Everything needed to use a map again in a later run: its keyframes (in id order), the pose
// graph's loop and relocalization edges (odometry edges follow from the keyframes), and the
// identity of what it was made with, so that a map is never used with another vocabulary (its
// words would mean other things) or another camera (its points and pixels would not fit).
struct SavedMap {
  std::uint64_t vocabulary_fingerprint = 0;
  geometry::StereoCamera camera;
  std::vector<SavedKeyframe> keyframes;
  std::vector<SavedEdge> edges;
};

// A versioned, checksummed binary file (io/binary_file: written through a temporary file,
// so a crash never leaves half a map under the real name).
void SaveMapFile(const std::string& path, const SavedMap& map);
// Throws io::InputError naming the file: unreadable, not a map, another version, truncated,
// failing its checksum, or inconsistent (ids out of order, an edge to an unknown keyframe).
SavedMap LoadMapFile(const std::string& path);

}  // namespace stereo_fabmap_slam::map
