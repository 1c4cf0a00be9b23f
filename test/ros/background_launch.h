#pragma once

// For rostests whose graph outlives its bag (euroc_bag.launch exit_at_end:=false) until the test
// has looked at it: roslaunch started in the background, the bag's end awaited on /clock, the
// launch interrupted.

#include <signal.h>

#include <cstdlib>
#include <mutex>
#include <string>

#include <ros/ros.h>
#include <rosgraph_msgs/Clock.h>

#include "test_support.h"

namespace stereo_fabmap_slam::test {

class BackgroundLaunch {
 public:
  // Starts `command` with its output in `log_path`. Watching /clock needs a spinner running.
  BackgroundLaunch(ros::NodeHandle& node, const std::string& command, const std::string& log_path)
      : clock_subscriber_(node.subscribe<rosgraph_msgs::Clock>(
            "/clock", 10, [this](const rosgraph_msgs::ClockConstPtr&) {
              std::lock_guard<std::mutex> lock(mutex_);
              last_clock_ = ros::WallTime::now();
            })) {
    const std::string pid_file = log_path + ".pid";
    if (std::system((command + " > " + log_path + " 2>&1 & echo $! > " + pid_file).c_str()) == 0)
      pid_ = std::stoi(ReadTextFile(pid_file));
  }
  ~BackgroundLaunch() { Interrupt(); }
  BackgroundLaunch(const BackgroundLaunch&) = delete;
  BackgroundLaunch& operator=(const BackgroundLaunch&) = delete;

  bool started() const { return pid_ > 0; }
  // The bag has ended when its clock has been silent for a second (or after `timeout`).
  void WaitForTheBagToEnd(ros::WallDuration timeout = ros::WallDuration(120)) const {
    const ros::WallTime deadline = ros::WallTime::now() + timeout;
    const auto playing = [&] {
      std::lock_guard<std::mutex> lock(mutex_);
      return last_clock_.isZero() || ros::WallTime::now() - last_clock_ < ros::WallDuration(1.0);
    };
    while (playing() && ros::WallTime::now() < deadline) ros::WallDuration(0.1).sleep();
  }
  // SIGINT, as Ctrl-C, and up to 30 s for roslaunch to take the graph down.
  void Interrupt() {
    if (pid_ <= 0) return;
    kill(pid_, SIGINT);
    for (int i = 0; i < 300 && kill(pid_, 0) == 0; ++i) ros::WallDuration(0.1).sleep();
    pid_ = 0;
  }

 private:
  mutable std::mutex mutex_;
  ros::WallTime last_clock_;
  ros::Subscriber clock_subscriber_;
  int pid_ = 0;
};

}  // namespace stereo_fabmap_slam::test
