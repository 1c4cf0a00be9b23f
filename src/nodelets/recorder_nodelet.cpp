// Recorder: what the graph did, written as run_dataset writes it (ros_wiring::RunRecorder over
// pipeline::RunRecord): into ~output, when the graph shuts down, trajectory.txt (map frame,
// every frame), odometry.txt, keyframes.txt, loops.csv, timing.csv and summary.json. It listens
// to the stages' outputs and changes nothing.
#include <cstdio>
#include <filesystem>
#include <memory>
#include <mutex>
#include <string>

#include <nodelet/nodelet.h>
#include <ros/ros.h>
#include <pluginlib/class_list_macros.hpp>

#include "parameter_reader.h"
#include "run_recorder.h"
#include "tracker_wiring.h"

namespace stereo_fabmap_slam {

class RecorderNodelet : public nodelet::Nodelet {
 public:
  ~RecorderNodelet() override {
    for (ros::Subscriber& subscriber : subscribers_) subscriber.shutdown();
    std::lock_guard<std::mutex> lock(mutex_);
    if (!recorder_) return;
    try {
      recorder_->Write(output_, std::filesystem::path(output_).filename().string());
      // On stderr: rosconsole has shut down with the node when the manager unloads its
      // nodelets, and its macros print nothing.
      std::fprintf(stderr, "[recorder] run written to %s: %zu frames\n", output_.c_str(),
                   recorder_->frames());
    } catch (const std::exception& error) {
      std::fprintf(stderr, "[recorder] run not written to %s: %s\n", output_.c_str(), error.what());
    }
  }

 private:
  void onInit() override;
  // Subscribes `topic`, handing each message to `handle` under the lock.
  template <typename Message, typename Handle>
  void Record(const std::string& topic, std::uint32_t queue, Handle handle) {
    subscribers_.push_back(getNodeHandle().subscribe<Message>(
        topic, queue, [this, handle](const boost::shared_ptr<const Message>& message) {
          std::lock_guard<std::mutex> lock(mutex_);
          handle(*message);
        }));
  }

  std::string output_;
  std::mutex mutex_;
  std::unique_ptr<ros_wiring::RunRecorder> recorder_;
  std::vector<ros::Subscriber> subscribers_;
};

void RecorderNodelet::onInit() {
  try {
    ros_parameters::RejectUnknownParameters(getPrivateNodeHandle(), {"loop_closing", "output"});
  } catch (const std::exception& error) {
    NODELET_FATAL_STREAM("bad configuration: " << error.what());
    throw;
  }
  output_ = getPrivateNodeHandle().param<std::string>("output", "");
  if (output_.empty()) {
    NODELET_ERROR("~output is not set: nothing will be written");
    return;
  }
  output_ = std::filesystem::absolute(output_).string();
  recorder_ =
      std::make_unique<ros_wiring::RunRecorder>(getPrivateNodeHandle().param("loop_closing", true));
  ros_wiring::RunRecorder& r = *recorder_;
  Record<stereo_fabmap_slam::TrackedFrame>("tracked_frames", 1000, [&r](const auto& m) {
    r.OnTrackedFrame(m, ros_wiring::WallSeconds());
  });
  Record<stereo_fabmap_slam::Keyframe>("keyframes", 100, [&r](const auto& m) { r.OnKeyframe(m); });
  Record<stereo_fabmap_slam::KeyframeUpdate>("keyframe_updates", 100,
                                             [&r](const auto& m) { r.OnUpdate(m); });
  Record<stereo_fabmap_slam::PlaceResult>("place_results", 100,
                                          [&r](const auto& m) { r.OnPlaceResult(m); });
  Record<stereo_fabmap_slam::MapGraph>("map_graph", 1, [&r](const auto& m) { r.OnMapGraph(m); });
  Record<stereo_fabmap_slam::MapLoaded>("map_loaded", 1, [this, &r](const auto& m) {
    const std::string problem = r.OnMapLoaded(m);
    if (!problem.empty()) NODELET_WARN("%s", problem.c_str());
  });
  Record<std_msgs::String>("mode", 1, [&r](const auto& m) { r.OnMode(m); });
  NODELET_INFO("recording the run into %s (written when the graph shuts down)", output_.c_str());
}

}  // namespace stereo_fabmap_slam

PLUGINLIB_EXPORT_CLASS(stereo_fabmap_slam::RecorderNodelet, nodelet::Nodelet)
