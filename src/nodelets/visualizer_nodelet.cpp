// Visualizer: draws what the others publish, touching nothing. map_graph, keyframes and
// odometry in; map_markers (keyframe frusta by map segment, odometry, loop and relocalization
// edges), map_path (the trajectory after loop closing), odometry_path and map_cloud out. The
// drawing is src/ros/ (map_markers, trajectory_paths, map_cloud); this file wires it.
#include <memory>
#include <mutex>
#include <string>

#include <nav_msgs/Odometry.h>
#include <nav_msgs/Path.h>
#include <nodelet/nodelet.h>
#include <ros/ros.h>
#include <sensor_msgs/PointCloud2.h>
#include <stereo_fabmap_slam/Keyframe.h>
#include <stereo_fabmap_slam/MapGraph.h>
#include <visualization_msgs/MarkerArray.h>
#include <pluginlib/class_list_macros.hpp>

#include "map_cloud.h"
#include "map_markers.h"
#include "parameter_reader.h"
#include "ros_conversions.h"
#include "trajectory_paths.h"

namespace stereo_fabmap_slam {

class VisualizerNodelet : public nodelet::Nodelet {
 private:
  void onInit() override;
  void OnGraph(const stereo_fabmap_slam::MapGraphConstPtr& graph);
  void OnKeyframe(const stereo_fabmap_slam::KeyframeConstPtr& keyframe);
  void OnOdometry(const nav_msgs::OdometryConstPtr& odometry);
  void OnTimer(const ros::WallTimerEvent&);

  ros_visualization::MarkerStyle style_;
  std::string map_frame_, odom_frame_;
  int max_path_poses_ = 5000, max_cloud_points_ = 200000;

  std::mutex mutex_;  // callbacks run on the manager's threads
  ros_visualization::TrajectoryPaths paths_;
  ros_visualization::MapCloud cloud_;
  stereo_fabmap_slam::MapGraphConstPtr graph_;
  bool graph_changed_ = false, paths_changed_ = false;

  ros::Subscriber graph_subscriber_, keyframe_subscriber_, odometry_subscriber_;
  ros::Publisher marker_publisher_, map_path_publisher_, odometry_path_publisher_, cloud_publisher_;
  ros::WallTimer timer_;
};

void VisualizerNodelet::onInit() {
  ros::NodeHandle& node = getNodeHandle();
  ros::NodeHandle& private_node = getPrivateNodeHandle();
  map_frame_ = private_node.param<std::string>("map_frame", "map");
  odom_frame_ = private_node.param<std::string>("odom_frame", "odom");
  style_.frustum_depth = private_node.param("frustum_depth", style_.frustum_depth);
  style_.line_width = private_node.param("line_width", style_.line_width);
  style_.edge_width = private_node.param("edge_width", style_.edge_width);
  // Bounds on what goes to rviz each refresh: an hour at 20 Hz is 72,000 poses, and a large
  // map millions of points; rviz stays fluid below these.
  max_path_poses_ = private_node.param("max_path_poses", max_path_poses_);
  max_cloud_points_ = private_node.param("max_cloud_points", max_cloud_points_);
  const double rate = private_node.param("rate", 5.0);  // [Hz] of path and map refreshes
  if (max_path_poses_ < 1 || max_cloud_points_ < 1 || rate <= 0 || style_.frustum_depth <= 0) {
    NODELET_FATAL("~max_path_poses, ~max_cloud_points, ~rate and ~frustum_depth must be > 0");
    throw std::runtime_error("bad Visualizer parameters");
  }
  try {
    ros_parameters::RejectUnknownParameters(
        private_node, {"edge_width", "frustum_depth", "line_width", "map_frame", "max_cloud_points",
                       "max_path_poses", "odom_frame", "rate"});
  } catch (const std::exception& error) {
    NODELET_FATAL_STREAM("bad configuration: " << error.what());
    throw;
  }

  // Latched: an rviz started later sees the map at once.
  marker_publisher_ = node.advertise<visualization_msgs::MarkerArray>("map_markers", 1, true);
  map_path_publisher_ = node.advertise<nav_msgs::Path>("map_path", 1, true);
  odometry_path_publisher_ = node.advertise<nav_msgs::Path>("odometry_path", 1, true);
  cloud_publisher_ = node.advertise<sensor_msgs::PointCloud2>("map_cloud", 1, true);
  graph_subscriber_ = node.subscribe("map_graph", 1, &VisualizerNodelet::OnGraph, this);
  keyframe_subscriber_ = node.subscribe("keyframes", 100, &VisualizerNodelet::OnKeyframe, this);
  odometry_subscriber_ = node.subscribe("odometry", 100, &VisualizerNodelet::OnOdometry, this);
  timer_ = node.createWallTimer(ros::WallDuration(1.0 / rate), &VisualizerNodelet::OnTimer, this);
}

void VisualizerNodelet::OnGraph(const stereo_fabmap_slam::MapGraphConstPtr& graph) {
  std::lock_guard<std::mutex> lock(mutex_);
  graph_ = graph;
  paths_.SetGraph(*graph);
  graph_changed_ = paths_changed_ = true;
}

void VisualizerNodelet::OnKeyframe(const stereo_fabmap_slam::KeyframeConstPtr& keyframe) {
  std::lock_guard<std::mutex> lock(mutex_);
  paths_.AddKeyframe(keyframe->id, keyframe->header.stamp,
                     ros_conversions::FromPoseMessage(keyframe->pose));
  cloud_.AddKeyframe(*keyframe);
}

void VisualizerNodelet::OnOdometry(const nav_msgs::OdometryConstPtr& odometry) {
  std::lock_guard<std::mutex> lock(mutex_);
  paths_.AddOdometry(odometry->header.stamp, ros_conversions::FromPoseMessage(odometry->pose.pose));
  paths_changed_ = true;
}

void VisualizerNodelet::OnTimer(const ros::WallTimerEvent&) {
  // Built under the lock, published outside it (publishing may copy to remote subscribers).
  std::unique_ptr<visualization_msgs::MarkerArray> markers;
  std::unique_ptr<sensor_msgs::PointCloud2> cloud;
  std::unique_ptr<nav_msgs::Path> map_path, odometry_path;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    if (graph_changed_ && graph_) {
      stereo_fabmap_slam::MapGraph graph = *graph_;
      graph.header.frame_id = map_frame_;
      markers = std::make_unique<visualization_msgs::MarkerArray>(
          ros_visualization::MapGraphMarkers(graph, style_));
      cloud = std::make_unique<sensor_msgs::PointCloud2>(
          cloud_.Build(graph, static_cast<std::size_t>(max_cloud_points_)));
      graph_changed_ = false;
    }
    if (paths_changed_) {
      map_path = std::make_unique<nav_msgs::Path>(
          paths_.MapPath(map_frame_, static_cast<std::size_t>(max_path_poses_)));
      odometry_path = std::make_unique<nav_msgs::Path>(
          paths_.OdometryPath(odom_frame_, static_cast<std::size_t>(max_path_poses_)));
      paths_changed_ = false;
    }
  }
  if (markers) marker_publisher_.publish(*markers);
  if (cloud) cloud_publisher_.publish(*cloud);
  if (map_path) map_path_publisher_.publish(*map_path);
  if (odometry_path) odometry_path_publisher_.publish(*odometry_path);
}

}  // namespace stereo_fabmap_slam

PLUGINLIB_EXPORT_CLASS(stereo_fabmap_slam::VisualizerNodelet, nodelet::Nodelet)
