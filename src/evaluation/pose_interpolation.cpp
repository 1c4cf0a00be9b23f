#include "stereo_fabmap_slam/evaluation/pose_interpolation.h"

#include <algorithm>

namespace stereo_fabmap_slam::evaluation {

std::optional<Eigen::Isometry3d> InterpolatePose(const Trajectory& trajectory, double time,
                                                 double max_gap) {
  const auto after =
      std::lower_bound(trajectory.begin(), trajectory.end(), time,
                       [](const StampedPose& pose, double t) { return pose.timestamp < t; });
  if (after == trajectory.end()) return std::nullopt;
  if (after->timestamp == time) return after->pose;
  if (after == trajectory.begin()) return std::nullopt;
  const StampedPose& before = *(after - 1);
  const double gap = after->timestamp - before.timestamp;
  if (gap > max_gap || gap <= 0) return std::nullopt;
  const double s = (time - before.timestamp) / gap;
  Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
  pose.translation() = (1 - s) * before.pose.translation() + s * after->pose.translation();
  pose.linear() = Eigen::Quaterniond(before.pose.linear())
                      .slerp(s, Eigen::Quaterniond(after->pose.linear()))
                      .toRotationMatrix();
  return pose;
}

}  // namespace stereo_fabmap_slam::evaluation
