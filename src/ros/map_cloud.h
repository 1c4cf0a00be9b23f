#pragma once

// The map's points as a PointCloud2 in the map frame: each map point once, placed by the first
// keyframe that saw it, so that the cloud follows the keyframes when loop closing moves them.

#include <cstdint>
#include <map>
#include <string>
#include <unordered_set>
#include <vector>

#include <sensor_msgs/PointCloud2.h>
#include <Eigen/Core>

#include <stereo_fabmap_slam/Keyframe.h>
#include <stereo_fabmap_slam/MapGraph.h>

namespace stereo_fabmap_slam::ros_visualization {

class MapCloud {
 public:
  // Keeps the keyframe's stereo points that are map points and that no other keyframe brought
  // (a keyframe sent again replaces its own).
  void AddKeyframe(const stereo_fabmap_slam::Keyframe& keyframe);

  // The points of the keyframes in `graph`, at their map poses; keyframes the graph does not
  // hold (yet) are left out. At most `max_points`, evenly thinned.
  sensor_msgs::PointCloud2 Build(const stereo_fabmap_slam::MapGraph& graph,
                                 std::size_t max_points) const;

  std::size_t points() const { return total_points_; }

 private:
  struct KeyframePoints {
    std::vector<std::int64_t> ids;
    std::vector<Eigen::Vector3f> points;  // camera frame
  };
  std::map<std::uint64_t, KeyframePoints> points_of_keyframe_;
  std::unordered_set<std::int64_t> seen_map_points_;
  std::size_t total_points_ = 0;
};

}  // namespace stereo_fabmap_slam::ros_visualization
