#include "transform_repeater.h"

#include <algorithm>

namespace stereo_fabmap_slam::ros_wiring {

void TransformRepeater::Sent(const geometry_msgs::TransformStamped& transform, double now) {
  std::lock_guard<std::mutex> lock(mutex_);
  last_[transform.child_frame_id] = transform;
  last_sent_ = now;
}

std::vector<geometry_msgs::TransformStamped> TransformRepeater::Due(double now,
                                                                    const ros::Time& clock) {
  std::lock_guard<std::mutex> lock(mutex_);
  std::vector<geometry_msgs::TransformStamped> due;
  if (last_.empty() || now - last_sent_ < period_) return due;
  last_sent_ = now;
  for (auto& [child, transform] : last_) {
    transform.header.stamp = std::max(clock, transform.header.stamp + ros::Duration(0, 1));
    due.push_back(transform);
  }
  return due;
}

}  // namespace stereo_fabmap_slam::ros_wiring
