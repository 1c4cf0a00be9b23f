#include "map_cloud.h"

#include <algorithm>

#include <sensor_msgs/point_cloud2_iterator.h>

#include "ros_conversions.h"

namespace stereo_fabmap_slam::ros_visualization {

void MapCloud::AddKeyframe(const stereo_fabmap_slam::Keyframe& keyframe) {
  KeyframePoints& kept = points_of_keyframe_[keyframe.id];
  // A keyframe sent again replaces its points: they are free for it to bring again.
  total_points_ -= kept.points.size();
  for (const std::int64_t id : kept.ids) seen_map_points_.erase(id);
  kept = KeyframePoints();
  for (std::size_t i = 0; i < keyframe.points.size() && i < keyframe.map_point_ids.size(); ++i) {
    const geometry_msgs::Point& p = keyframe.points[i];
    if (keyframe.map_point_ids[i] < 0 || p.z <= 0) continue;
    if (!seen_map_points_.insert(keyframe.map_point_ids[i]).second) continue;
    kept.ids.push_back(keyframe.map_point_ids[i]);
    kept.points.emplace_back(p.x, p.y, p.z);
  }
  total_points_ += kept.points.size();
}

sensor_msgs::PointCloud2 MapCloud::Build(const stereo_fabmap_slam::MapGraph& graph,
                                         std::size_t max_points) const {
  std::size_t available = 0;
  for (const std::uint64_t id : graph.keyframe_ids) {
    const auto found = points_of_keyframe_.find(id);
    if (found != points_of_keyframe_.end()) available += found->second.points.size();
  }
  // Every stride-th point: at most max_points (at least one point a stride).
  const std::size_t limit = std::max<std::size_t>(1, max_points);
  const std::size_t stride = std::max<std::size_t>(1, (available + limit - 1) / limit);
  const std::size_t kept = (available + stride - 1) / stride;

  sensor_msgs::PointCloud2 cloud;
  cloud.header = graph.header;
  sensor_msgs::PointCloud2Modifier modifier(cloud);
  modifier.setPointCloud2FieldsByString(1, "xyz");
  modifier.resize(kept);
  sensor_msgs::PointCloud2Iterator<float> x(cloud, "x"), y(cloud, "y"), z(cloud, "z");
  std::size_t index = 0;
  for (std::size_t k = 0; k < graph.keyframe_ids.size() && k < graph.keyframe_poses.size(); ++k) {
    const auto found = points_of_keyframe_.find(graph.keyframe_ids[k]);
    if (found == points_of_keyframe_.end()) continue;
    const Eigen::Isometry3f T_map_camera =
        ros_conversions::FromPoseMessage(graph.keyframe_poses[k]).cast<float>();
    for (const Eigen::Vector3f& point : found->second.points) {
      if (index++ % stride != 0) continue;
      const Eigen::Vector3f in_map = T_map_camera * point;
      *x = in_map.x();
      *y = in_map.y();
      *z = in_map.z();
      ++x, ++y, ++z;
    }
  }
  return cloud;
}

}  // namespace stereo_fabmap_slam::ros_visualization
