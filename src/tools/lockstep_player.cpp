// Plays a stereo bag into the nodelet graph one pair at a time: each pair (and its camera_info,
// and /clock at its stamp) is published only when the StereoTracker has said, on tracked_frames,
// that the pair before is done, which in lockstep mode (the tracker's ~lockstep) is after the
// Backend and the LoopDetector have answered it. Nothing is skipped and every stage sees its
// inputs in the order run_dataset uses, so the graph computes what run_dataset computes.
#include <chrono>
#include <condition_variable>
#include <cstdio>
#include <map>
#include <mutex>
#include <optional>
#include <set>
#include <string>
#include <thread>
#include <vector>

#include <ros/master.h>
#include <ros/ros.h>
#include <rosbag/bag.h>
#include <rosbag/view.h>
#include <rosgraph_msgs/Clock.h>
#include <sensor_msgs/CameraInfo.h>
#include <sensor_msgs/Image.h>
#include <stereo_fabmap_slam/TrackedFrame.h>

#include "command_line.h"

namespace {

using namespace stereo_fabmap_slam;  // NOLINT: a tool's main file

constexpr char kUsage[] =
    "usage: lockstep_player BAG [--left TOPIC] [--right TOPIC] [--wait-for TOPIC,...]\n"
    "                       [--timeout SECONDS] [--delay SECONDS]\n"
    "Plays the stereo pairs of BAG (default topics /cam0/image_raw and /cam1/image_raw, with\n"
    "their camera_info if the bag has it) one at a time, publishing /clock at each pair's stamp,\n"
    "and waits for the StereoTracker's tracked_frames message of each pair before the next (at\n"
    "most --timeout seconds, default 60). Starts once tracked_frames and the --wait-for topics\n"
    "are advertised (default: map_graph), then --delay seconds more (default 1). Run it under\n"
    "use_sim_time with the tracker's ~lockstep (euroc_bag.launch lockstep:=true).\n";

// Whether every topic is advertised on the master.
bool Advertised(const std::set<std::string>& topics) {
  ros::master::V_TopicInfo infos;
  if (!ros::master::getTopics(infos)) return false;
  std::set<std::string> present;
  for (const ros::master::TopicInfo& info : infos) present.insert(info.name);
  for (const std::string& topic : topics) {
    if (present.count(topic) == 0) return false;
  }
  return true;
}

class DoneFrames {
 public:
  void OnFrame(const stereo_fabmap_slam::TrackedFrameConstPtr& frame) {
    {
      std::lock_guard<std::mutex> lock(mutex_);
      done_.insert(frame->header.stamp);
    }
    changed_.notify_all();
  }
  bool WaitFor(const ros::Time& stamp, double timeout) {
    std::unique_lock<std::mutex> lock(mutex_);
    return changed_.wait_for(lock, std::chrono::duration<double>(timeout), [&] {
      return done_.count(stamp) > 0 || !ros::ok();
    }) && ros::ok();
  }

 private:
  std::mutex mutex_;
  std::condition_variable changed_;
  std::set<ros::Time> done_;
};

}  // namespace

int main(int argc, char** argv) {
  ros::init(argc, argv, "lockstep_player", ros::init_options::NoSigintHandler);
  std::optional<tools::CommandLine> args;
  try {
    args.emplace(argc, argv, std::set<std::string>{"left", "right", "wait-for", "timeout", "delay"},
                 std::set<std::string>{"help"});
    if (args->Flag("help")) {
      std::fputs(kUsage, stdout);
      return 0;
    }
    if (args->positional().size() != 1) throw std::invalid_argument("expected one BAG");
  } catch (const std::invalid_argument& error) {
    std::fprintf(stderr, "lockstep_player: %s\n%s", error.what(), kUsage);
    return 2;
  }
  try {
    const std::string left_topic = args->ValueOr("left", "/cam0/image_raw");
    const std::string right_topic = args->ValueOr("right", "/cam1/image_raw");
    const std::string left_info_topic =
        left_topic.substr(0, left_topic.rfind('/')) + "/camera_info";
    const std::string right_info_topic =
        right_topic.substr(0, right_topic.rfind('/')) + "/camera_info";
    const double timeout = args->NumberOr("timeout", 60.0);
    rosbag::Bag bag(args->positional()[0], rosbag::bagmode::Read);
    ros::NodeHandle node;
    ros::Publisher clock = node.advertise<rosgraph_msgs::Clock>("/clock", 1);
    ros::Publisher left = node.advertise<sensor_msgs::Image>(left_topic, 2);
    ros::Publisher right = node.advertise<sensor_msgs::Image>(right_topic, 2);
    ros::Publisher left_info = node.advertise<sensor_msgs::CameraInfo>(left_info_topic, 2);
    ros::Publisher right_info = node.advertise<sensor_msgs::CameraInfo>(right_info_topic, 2);
    DoneFrames done;
    ros::Subscriber frames = node.subscribe<stereo_fabmap_slam::TrackedFrame>(
        "tracked_frames", 100,
        [&done](const stereo_fabmap_slam::TrackedFrameConstPtr& m) { done.OnFrame(m); });
    ros::AsyncSpinner spinner(1);
    spinner.start();

    std::set<std::string> wait_for = {node.resolveName("tracked_frames")};
    const std::string topics = args->ValueOr("wait-for", "map_graph") + ",";
    for (std::size_t begin = 0, end; (end = topics.find(',', begin)) != std::string::npos;
         begin = end + 1) {
      if (end > begin) wait_for.insert(node.resolveName(topics.substr(begin, end - begin)));
    }
    while (ros::ok() && (!Advertised(wait_for) || left.getNumSubscribers() == 0 ||
                         right.getNumSubscribers() == 0)) {
      std::this_thread::sleep_for(std::chrono::milliseconds(100));
    }
    std::this_thread::sleep_for(std::chrono::duration<double>(args->NumberOr("delay", 1.0)));

    // The bag in time order; each half of a pair waits for its partner (equal stamps).
    rosbag::View view(bag, rosbag::TopicQuery(std::vector<std::string>{
                               left_topic, right_topic, left_info_topic, right_info_topic}));
    std::map<ros::Time, sensor_msgs::ImageConstPtr> lefts, rights;
    std::map<ros::Time, sensor_msgs::CameraInfoConstPtr> left_infos, right_infos;
    std::size_t pairs = 0, unanswered = 0;
    for (const rosbag::MessageInstance& instance : view) {
      if (!ros::ok()) break;
      std::optional<ros::Time> complete;
      if (const auto image = instance.instantiate<sensor_msgs::Image>()) {
        auto& mine = instance.getTopic() == left_topic ? lefts : rights;
        const auto& other = instance.getTopic() == left_topic ? rights : lefts;
        mine[image->header.stamp] = image;
        if (other.count(image->header.stamp) > 0) complete = image->header.stamp;
      } else if (const auto info = instance.instantiate<sensor_msgs::CameraInfo>()) {
        (instance.getTopic() == left_info_topic ? left_infos : right_infos)[info->header.stamp] =
            info;
      }
      if (!complete) continue;
      const ros::Time stamp = *complete;
      rosgraph_msgs::Clock now;
      now.clock = stamp;
      clock.publish(now);
      if (left_infos.count(stamp) > 0 && right_infos.count(stamp) > 0) {
        left_info.publish(left_infos[stamp]);
        right_info.publish(right_infos[stamp]);
      }
      left.publish(lefts[stamp]);
      right.publish(rights[stamp]);
      ++pairs;
      if (!done.WaitFor(stamp, timeout)) {
        ++unanswered;
        std::fprintf(stderr,
                     "lockstep_player: no tracked_frames for the pair at %.3f within %g s\n",
                     stamp.toSec(), timeout);
      }
      // Older halves can no longer pair up.
      for (auto* halves : {&lefts, &rights})
        halves->erase(halves->begin(), halves->upper_bound(stamp));
      left_infos.erase(left_infos.begin(), left_infos.upper_bound(stamp));
      right_infos.erase(right_infos.begin(), right_infos.upper_bound(stamp));
    }
    std::printf("lockstep_player: played %zu stereo pairs, %zu without an answer\n", pairs,
                unanswered);
    return unanswered == 0 ? 0 : 1;
  } catch (const std::exception& error) {
    std::fprintf(stderr, "lockstep_player: %s\n", error.what());
    return 1;
  }
}
