#pragma once
// The last transforms of a broadcaster, said again while nothing new comes (the bag ended or
// paused, the camera stopped), so that tf tools started then (tf_echo, view_frames, an rviz
// opened later) still find the frames: /tf is not latched, and without a repeat they would find
// nothing while the graph stays up for inspection.
#include <map>
#include <mutex>
#include <string>
#include <vector>

#include <geometry_msgs/TransformStamped.h>

namespace stereo_fabmap_slam::ros_wiring {

class TransformRepeater {
 public:
  // `period` [s, wall time]: how long nothing new comes before a repeat, and between repeats.
  // A second: a listener that starts waits at most that long, and a live camera at any rate
  // sends more often, so it is never repeated while it streams.
  explicit TransformRepeater(double period = 1.0) : period_(period) {}

  // A transform just broadcast, at wall time `now` [s]. Any thread.
  void Sent(const geometry_msgs::TransformStamped& transform, double now);
  // What to broadcast again at wall time `now`: every transform sent, once a period passed
  // without a new one, stamped at the ROS `clock` or, if that is not after its last stamp, a
  // nanosecond after it. A listener that has the last one takes the repeat as new data, not as
  // the same stamp again, which tf2 refuses with a TF_REPEATED_DATA error every time; the clock
  // (a bag's, stopped) need not move. Stamped at the clock where it can be, the repeats of
  // several nodelets (odom -> base_link, map -> odom) lie within nanoseconds of each other, so a
  // listener finds the whole chain at one time. Any thread.
  std::vector<geometry_msgs::TransformStamped> Due(double now, const ros::Time& clock);

 private:
  double period_;
  std::mutex mutex_;
  std::map<std::string, geometry_msgs::TransformStamped> last_;  // by child frame
  double last_sent_ = 0;  // [s, wall] of the last transform or repeat
};

}  // namespace stereo_fabmap_slam::ros_wiring
