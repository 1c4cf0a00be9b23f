#include "trajectory_paths.h"

#include "ros_conversions.h"

namespace stereo_fabmap_slam::ros_visualization {
namespace {

// Indices 0 .. n-1 thinned to at most max_count, evenly spaced, the last one always included.
std::vector<std::size_t> ThinnedIndices(std::size_t n, std::size_t max_count) {
  std::vector<std::size_t> indices;
  if (n == 0 || max_count == 0) return indices;
  const std::size_t stride = (n + max_count - 1) / max_count;
  for (std::size_t i = (n - 1) % stride; i < n; i += stride) indices.push_back(i);
  return indices;
}

geometry_msgs::PoseStamped Stamped(const ros::Time& stamp, const std::string& frame,
                                   const Eigen::Isometry3d& pose) {
  geometry_msgs::PoseStamped stamped;
  stamped.header.stamp = stamp;
  stamped.header.frame_id = frame;
  stamped.pose = ros_conversions::ToPoseMessage(pose);
  return stamped;
}

}  // namespace

void TrajectoryPaths::AddOdometry(const ros::Time& stamp, const Eigen::Isometry3d& T_odom_base) {
  if (!frames_.empty() && stamp < frames_.back().stamp) {
    // Time went backwards (a bag played again): the tracker started over, and so do the paths.
    frames_.clear();
    keyframes_by_stamp_.erase(keyframes_by_stamp_.upper_bound(stamp), keyframes_by_stamp_.end());
  }
  frames_.push_back({stamp, T_odom_base});
}

void TrajectoryPaths::AddKeyframe(std::uint64_t id, const ros::Time& stamp,
                                  const Eigen::Isometry3d& T_odom_camera) {
  keyframes_by_stamp_[stamp] = {id, T_odom_camera};
}

void TrajectoryPaths::SetGraph(const stereo_fabmap_slam::MapGraph& graph) {
  map_poses_.clear();
  for (std::size_t i = 0; i < graph.keyframe_ids.size() && i < graph.keyframe_poses.size(); ++i) {
    map_poses_[graph.keyframe_ids[i]] = ros_conversions::FromPoseMessage(graph.keyframe_poses[i]);
  }
  T_map_odom_ = ros_conversions::FromTransformMessage(graph.map_to_odom);
}

nav_msgs::Path TrajectoryPaths::OdometryPath(const std::string& odom_frame,
                                             std::size_t max_poses) const {
  nav_msgs::Path path;
  path.header.frame_id = odom_frame;
  for (std::size_t i : ThinnedIndices(frames_.size(), max_poses)) {
    path.poses.push_back(Stamped(frames_[i].stamp, odom_frame, frames_[i].T_odom_base));
  }
  if (!frames_.empty()) path.header.stamp = frames_.back().stamp;
  return path;
}

nav_msgs::Path TrajectoryPaths::MapPath(const std::string& map_frame, std::size_t max_poses) const {
  nav_msgs::Path path;
  path.header.frame_id = map_frame;
  for (std::size_t i : ThinnedIndices(frames_.size(), max_poses)) {
    const Frame& frame = frames_[i];
    // The frame's keyframe: the latest at or before it. Its map pose, or, before the graph
    // holds it (or never will, in localization mode), its odometry moved by map -> odom.
    Eigen::Isometry3d T_map_base = T_map_odom_ * frame.T_odom_base;
    auto keyframe = keyframes_by_stamp_.upper_bound(frame.stamp);
    if (keyframe != keyframes_by_stamp_.begin()) {
      --keyframe;
      const auto map_pose = map_poses_.find(keyframe->second.id);
      if (map_pose != map_poses_.end()) {
        T_map_base =
            map_pose->second * keyframe->second.T_odom_camera.inverse() * frame.T_odom_base;
      }
    }
    path.poses.push_back(Stamped(frame.stamp, map_frame, T_map_base));
  }
  if (!frames_.empty()) path.header.stamp = frames_.back().stamp;
  return path;
}

}  // namespace stereo_fabmap_slam::ros_visualization
