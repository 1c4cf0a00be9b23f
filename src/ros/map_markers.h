#pragma once

// The map graph as rviz markers: keyframes as small camera frusta coloured by map segment,
// odometry edges, loop edges and relocalization edges (rtabmap's convention: neighbours blue,
// loops red), relocalized keyframes marked.

#include <cstdint>
#include <map>
#include <string>

#include <ros/time.h>
#include <visualization_msgs/MarkerArray.h>

#include <stereo_fabmap_slam/MapGraph.h>

namespace stereo_fabmap_slam::ros_visualization {

struct MarkerStyle {
  double frustum_depth = 0.15;  // [m] from the optical centre to the image plane drawn
  double frustum_aspect = 1.5;  // image width / height
  double frustum_fov_deg = 70;  // horizontal
  double line_width = 0.01;     // [m]
  double edge_width = 0.04;     // [m] loop and relocalization edges: short, drawn thick
};

// The marker namespaces, one marker each (id 0), so that a display can turn them on and off.
inline constexpr char kKeyframesNamespace[] = "keyframes";
inline constexpr char kOdometryEdgesNamespace[] = "odometry_edges";
inline constexpr char kLoopEdgesNamespace[] = "loop_edges";
inline constexpr char kRelocalizationEdgesNamespace[] = "relocalization_edges";
inline constexpr char kRelocalizedNamespace[] = "relocalized_keyframes";
// Line segments in a keyframe frustum's LINE_LIST: 4 from the centre, 4 around the image.
inline constexpr int kFrustumSegments = 8;

// The map segment of each keyframe of the graph: keyframes joined by odometry edges form one
// segment of odometry (a loss starts a new one). Numbered from 0 in order of their first id.
std::map<std::uint64_t, int> MapSegments(const stereo_fabmap_slam::MapGraph& graph);

// All five markers in the graph's frame. A namespace with nothing to draw gets a DELETE
// (rviz refuses empty line lists), so that old content disappears too.
visualization_msgs::MarkerArray MapGraphMarkers(const stereo_fabmap_slam::MapGraph& graph,
                                                const MarkerStyle& style);

}  // namespace stereo_fabmap_slam::ros_visualization
