#pragma once

// The two paths a SLAM user compares in rviz: the odometry as published (odom frame), and the
// trajectory after loop closing (map frame), where every frame follows the keyframe it was
// tracked after, so that a loop closure or relocalization bends the whole path, not only its
// end.

#include <cstdint>
#include <map>
#include <string>
#include <vector>

#include <nav_msgs/Path.h>
#include <ros/time.h>
#include <Eigen/Geometry>

#include <stereo_fabmap_slam/MapGraph.h>

namespace stereo_fabmap_slam::ros_visualization {

class TrajectoryPaths {
 public:
  // A frame's odometry (the base in odom), in time order as odometry comes; a frame older than
  // the last starts the paths over.
  void AddOdometry(const ros::Time& stamp, const Eigen::Isometry3d& T_odom_base);
  // A keyframe as the tracker published it (its camera in odom): the pose the frames after it
  // were tracked with, so each frame keeps its place relative to it (bundle adjustment's later
  // refinements move the keyframe in map_graph, and the frame with it).
  void AddKeyframe(std::uint64_t id, const ros::Time& stamp,
                   const Eigen::Isometry3d& T_odom_camera);
  // The Backend's latest graph: keyframes' map poses and map -> odom.
  void SetGraph(const stereo_fabmap_slam::MapGraph& graph);

  // At most `max_poses` poses, evenly thinned out (always keeping the newest), in each path.
  nav_msgs::Path OdometryPath(const std::string& odom_frame, std::size_t max_poses) const;
  nav_msgs::Path MapPath(const std::string& map_frame, std::size_t max_poses) const;

  std::size_t frames() const { return frames_.size(); }

 private:
  struct Frame {
    ros::Time stamp;
    Eigen::Isometry3d T_odom_base;
  };
  struct KeyframeInOdom {
    std::uint64_t id;
    Eigen::Isometry3d T_odom_camera;
  };
  std::vector<Frame> frames_;
  std::map<ros::Time, KeyframeInOdom> keyframes_by_stamp_;
  std::map<std::uint64_t, Eigen::Isometry3d> map_poses_;  // T_map_camera of the graph
  Eigen::Isometry3d T_map_odom_ = Eigen::Isometry3d::Identity();
};

}  // namespace stereo_fabmap_slam::ros_visualization
