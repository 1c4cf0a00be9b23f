#include "map_markers.h"

#include <cmath>
#include <numeric>
#include <vector>

#include <Eigen/Geometry>

#include "ros_conversions.h"

namespace stereo_fabmap_slam::ros_visualization {
namespace {

using stereo_fabmap_slam::MapGraph;
using stereo_fabmap_slam::MapGraphEdge;

// Distinct colours for successive map segments (a qualitative palette, without the edges' red,
// blue and magenta and the path's yellow).
std_msgs::ColorRGBA SegmentColor(int segment) {
  static constexpr float kPalette[][3] = {{0.10f, 0.75f, 0.20f}, {0.95f, 0.60f, 0.05f},
                                          {0.60f, 0.30f, 0.80f}, {0.10f, 0.75f, 0.75f},
                                          {0.60f, 0.60f, 0.95f}, {0.55f, 0.35f, 0.20f}};
  const auto& rgb = kPalette[segment % 6];
  std_msgs::ColorRGBA color;
  color.r = rgb[0];
  color.g = rgb[1];
  color.b = rgb[2];
  color.a = 1.0f;
  return color;
}

std_msgs::ColorRGBA Color(float r, float g, float b) {
  std_msgs::ColorRGBA color;
  color.r = r;
  color.g = g;
  color.b = b;
  color.a = 1.0f;
  return color;
}

geometry_msgs::Point ToPoint(const Eigen::Vector3d& v) {
  geometry_msgs::Point point;
  point.x = v.x();
  point.y = v.y();
  point.z = v.z();
  return point;
}

visualization_msgs::Marker NewMarker(const MapGraph& graph, const char* name, int type,
                                     double width, const std_msgs::ColorRGBA& color) {
  visualization_msgs::Marker marker;
  marker.header = graph.header;
  marker.ns = name;
  marker.id = 0;
  marker.type = type;
  marker.action = visualization_msgs::Marker::ADD;
  marker.pose.orientation.w = 1.0;
  marker.scale.x = width;
  marker.scale.y = width;
  marker.scale.z = width;
  marker.color = color;
  return marker;
}

// Parent lookup of a union-find over keyframe indices.
std::size_t Root(std::vector<std::size_t>& parent, std::size_t i) {
  while (parent[i] != i) i = parent[i] = parent[parent[i]];
  return i;
}

}  // namespace

std::map<std::uint64_t, int> MapSegments(const MapGraph& graph) {
  std::map<std::uint64_t, std::size_t> index;
  for (std::size_t i = 0; i < graph.keyframe_ids.size(); ++i) index[graph.keyframe_ids[i]] = i;
  std::vector<std::size_t> parent(graph.keyframe_ids.size());
  std::iota(parent.begin(), parent.end(), 0);
  for (const MapGraphEdge& edge : graph.edges) {
    if (edge.type != MapGraphEdge::ODOMETRY) continue;
    const auto from = index.find(edge.from_id), to = index.find(edge.to_id);
    if (from == index.end() || to == index.end()) continue;
    parent[Root(parent, from->second)] = Root(parent, to->second);
  }
  // Number the segments in order of their smallest keyframe id (index is ordered by id).
  std::map<std::size_t, int> number_of_root;
  std::map<std::uint64_t, int> segments;
  for (const auto& [id, i] : index) {
    const std::size_t root = Root(parent, i);
    const auto found = number_of_root.emplace(root, static_cast<int>(number_of_root.size()));
    segments[id] = found.first->second;
  }
  return segments;
}

visualization_msgs::MarkerArray MapGraphMarkers(const MapGraph& graph, const MarkerStyle& style) {
  std::map<std::uint64_t, Eigen::Isometry3d> poses;
  for (std::size_t i = 0; i < graph.keyframe_ids.size() && i < graph.keyframe_poses.size(); ++i) {
    poses[graph.keyframe_ids[i]] = ros_conversions::FromPoseMessage(graph.keyframe_poses[i]);
  }
  const std::map<std::uint64_t, int> segments = MapSegments(graph);

  visualization_msgs::Marker keyframes =
      NewMarker(graph, kKeyframesNamespace, visualization_msgs::Marker::LINE_LIST, style.line_width,
                Color(0.1f, 0.75f, 0.2f));
  // The frustum in the optical frame (z forward, x right, y down): centre and image corners.
  const double half_width =
      style.frustum_depth * std::tan(0.5 * style.frustum_fov_deg * M_PI / 180.0);
  const double half_height = half_width / style.frustum_aspect;
  const Eigen::Vector3d corners[4] = {{-half_width, -half_height, style.frustum_depth},
                                      {half_width, -half_height, style.frustum_depth},
                                      {half_width, half_height, style.frustum_depth},
                                      {-half_width, half_height, style.frustum_depth}};
  for (const auto& [id, pose] : poses) {
    const std_msgs::ColorRGBA color = SegmentColor(segments.at(id));
    const geometry_msgs::Point centre = ToPoint(pose.translation());
    for (int k = 0; k < 4; ++k) {
      const geometry_msgs::Point corner = ToPoint(pose * corners[k]);
      const geometry_msgs::Point next = ToPoint(pose * corners[(k + 1) % 4]);
      keyframes.points.insert(keyframes.points.end(), {centre, corner, corner, next});
      keyframes.colors.insert(keyframes.colors.end(), 4, color);
    }
  }

  visualization_msgs::Marker odometry =
      NewMarker(graph, kOdometryEdgesNamespace, visualization_msgs::Marker::LINE_LIST,
                style.line_width, Color(0.15f, 0.35f, 0.95f));
  visualization_msgs::Marker loops =
      NewMarker(graph, kLoopEdgesNamespace, visualization_msgs::Marker::LINE_LIST, style.edge_width,
                Color(0.95f, 0.1f, 0.1f));
  visualization_msgs::Marker relocalizations =
      NewMarker(graph, kRelocalizationEdgesNamespace, visualization_msgs::Marker::LINE_LIST,
                style.edge_width, Color(0.95f, 0.2f, 0.85f));
  visualization_msgs::Marker relocalized =
      NewMarker(graph, kRelocalizedNamespace, visualization_msgs::Marker::SPHERE_LIST,
                4 * style.edge_width, Color(0.95f, 0.2f, 0.85f));
  for (const MapGraphEdge& edge : graph.edges) {
    const auto from = poses.find(edge.from_id), to = poses.find(edge.to_id);
    if (from == poses.end() || to == poses.end()) continue;
    const geometry_msgs::Point a = ToPoint(from->second.translation());
    const geometry_msgs::Point b = ToPoint(to->second.translation());
    switch (edge.type) {
      case MapGraphEdge::ODOMETRY:
        odometry.points.insert(odometry.points.end(), {a, b});
        break;
      case MapGraphEdge::LOOP:
        loops.points.insert(loops.points.end(), {a, b});
        break;
      default:
        relocalizations.points.insert(relocalizations.points.end(), {a, b});
        relocalized.points.push_back(b);  // the keyframe of the piece that was found
        break;
    }
  }

  visualization_msgs::MarkerArray array;
  for (visualization_msgs::Marker* marker :
       {&keyframes, &odometry, &loops, &relocalizations, &relocalized}) {
    if (marker->points.empty()) {
      marker->action = visualization_msgs::Marker::DELETE;
      marker->colors.clear();
    }
    array.markers.push_back(*marker);
  }
  return array;
}

}  // namespace stereo_fabmap_slam::ros_visualization
