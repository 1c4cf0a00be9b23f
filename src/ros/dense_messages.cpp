#include "dense_messages.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <unordered_set>
#include <vector>

#include <sensor_msgs/point_cloud2_iterator.h>

namespace stereo_fabmap_slam::ros_visualization {
namespace {

// A cell's integer coordinates packed into one key (21 bits each: +-1 million cells, 50 km at
// 5 cm).
std::uint64_t CellKey(const Eigen::Vector3d& point, double cell) {
  const auto coordinate = [cell](double value) {
    return static_cast<std::uint64_t>(static_cast<std::int64_t>(std::floor(value / cell)) +
                                      (1 << 20)) &
           0x1FFFFF;
  };
  return coordinate(point.x()) << 42 | coordinate(point.y()) << 21 | coordinate(point.z());
}

}  // namespace

sensor_msgs::PointCloud2 DenseCloudMessage(const dense::Cloud& cloud, double cell,
                                           const std::string& frame, const ros::Time& stamp) {
  std::vector<std::size_t> kept;
  std::unordered_set<std::uint64_t> cells;
  for (std::size_t i = 0; i < cloud.points.size(); ++i) {
    if (cell <= 0 || cells.insert(CellKey(cloud.points[i], cell)).second) kept.push_back(i);
  }
  sensor_msgs::PointCloud2 message;
  message.header.frame_id = frame;
  message.header.stamp = stamp;
  sensor_msgs::PointCloud2Modifier modifier(message);
  modifier.setPointCloud2Fields(
      4, "x", 1, sensor_msgs::PointField::FLOAT32, "y", 1, sensor_msgs::PointField::FLOAT32, "z", 1,
      sensor_msgs::PointField::FLOAT32, "intensity", 1, sensor_msgs::PointField::FLOAT32);
  modifier.resize(kept.size());
  sensor_msgs::PointCloud2Iterator<float> x(message, "x"), y(message, "y"), z(message, "z"),
      intensity(message, "intensity");
  for (const std::size_t i : kept) {
    *x = static_cast<float>(cloud.points[i].x());
    *y = static_cast<float>(cloud.points[i].y());
    *z = static_cast<float>(cloud.points[i].z());
    *intensity = i < cloud.grey.size() ? cloud.grey[i] : 0.0f;
    ++x, ++y, ++z, ++intensity;
  }
  return message;
}

visualization_msgs::Marker DenseMeshMarker(const dense::Mesh& mesh, std::size_t max_triangles,
                                           const std::string& frame, const ros::Time& stamp) {
  visualization_msgs::Marker marker;
  marker.header.frame_id = frame;
  marker.header.stamp = stamp;
  marker.ns = "dense_mesh";
  marker.id = 0;
  marker.type = visualization_msgs::Marker::TRIANGLE_LIST;
  marker.action = visualization_msgs::Marker::ADD;
  marker.pose.orientation.w = 1.0;
  marker.scale.x = marker.scale.y = marker.scale.z = 1.0;
  marker.color.a = 1.0;
  const std::size_t step =
      max_triangles == 0 ? 1 : (mesh.triangles.size() + max_triangles - 1) / max_triangles;
  for (std::size_t t = 0; t < mesh.triangles.size(); t += std::max<std::size_t>(step, 1)) {
    for (int corner = 0; corner < 3; ++corner) {
      const auto index = static_cast<std::size_t>(mesh.triangles[t][corner]);
      geometry_msgs::Point point;
      point.x = mesh.vertices[index].x();
      point.y = mesh.vertices[index].y();
      point.z = mesh.vertices[index].z();
      marker.points.push_back(point);
      std_msgs::ColorRGBA colour;
      colour.r = colour.g = colour.b = index < mesh.grey.size() ? mesh.grey[index] : 0.5f;
      colour.a = 1.0f;
      marker.colors.push_back(colour);
    }
  }
  return marker;
}

}  // namespace stereo_fabmap_slam::ros_visualization
