// Recorder: what the graph did, written as run_dataset writes it (pipeline::RunRecord): into
// ~output, when the graph shuts down, trajectory.txt (map frame, every frame), odometry.txt,
// keyframes.txt, loops.csv, timing.csv and summary.json. It listens to the stages' outputs
// (tracked_frames, keyframes, keyframe_updates, place_results, map_graph, map_loaded, mode)
// and changes nothing.
#include <filesystem>
#include <memory>
#include <mutex>
#include <optional>
#include <string>

#include <nodelet/nodelet.h>
#include <ros/ros.h>
#include <std_msgs/String.h>
#include <stereo_fabmap_slam/MapLoaded.h>
#include <pluginlib/class_list_macros.hpp>

#include "ros_conversions.h"
#include "stage_conversions.h"
#include "stereo_fabmap_slam/map/map_file.h"
#include "stereo_fabmap_slam/pipeline/run_record.h"
#include "tracker_wiring.h"

namespace stereo_fabmap_slam {

class RecorderNodelet : public nodelet::Nodelet {
 public:
  ~RecorderNodelet() override {
    for (ros::Subscriber* subscriber :
         {&frame_subscriber_, &keyframe_subscriber_, &update_subscriber_, &place_subscriber_,
          &graph_subscriber_, &loaded_subscriber_, &mode_subscriber_}) {
      subscriber->shutdown();
    }
    std::lock_guard<std::mutex> lock(mutex_);
    Write();
  }

 private:
  void onInit() override;
  void Write();  // call with mutex_

  std::string output_;
  bool loop_closing_ = true;  // without it the map trajectory is the odometry's, as offline
  std::mutex mutex_;
  pipeline::RunRecord record_;
  std::optional<pipeline::MapSnapshot> map_;
  pipeline::InputCounts counts_;
  std::string mode_ = "mapping";
  std::size_t map_keyframes_loaded_ = 0;
  double first_wall_ = 0, last_wall_ = 0;  // [s] when the first and last frames came
  ros::Subscriber frame_subscriber_, keyframe_subscriber_, update_subscriber_, place_subscriber_,
      graph_subscriber_, loaded_subscriber_, mode_subscriber_;
};

void RecorderNodelet::onInit() {
  output_ = getPrivateNodeHandle().param<std::string>("output", "");
  if (output_.empty()) {
    NODELET_ERROR("~output is not set: nothing will be written");
    return;
  }
  output_ = std::filesystem::absolute(output_).string();
  loop_closing_ = getPrivateNodeHandle().param("loop_closing", true);
  ros::NodeHandle& node = getNodeHandle();
  frame_subscriber_ = node.subscribe<stereo_fabmap_slam::TrackedFrame>(
      "tracked_frames", 1000, [this](const stereo_fabmap_slam::TrackedFrameConstPtr& m) {
        std::lock_guard<std::mutex> lock(mutex_);
        last_wall_ = ros_wiring::WallSeconds();
        if (first_wall_ == 0) first_wall_ = last_wall_;
        counts_ = {m->pairs_received, counts_.tracked + (m->tracked ? 1 : 0), m->pairs_refused,
                   m->pairs_skipped};
        if (m->tracked) record_.AddFrame(ros_conversions::FromTrackedFrameMessage(*m));
      });
  keyframe_subscriber_ = node.subscribe<stereo_fabmap_slam::Keyframe>(
      "keyframes", 100, [this](const stereo_fabmap_slam::KeyframeConstPtr& m) {
        std::lock_guard<std::mutex> lock(mutex_);
        record_.AddKeyframe(static_cast<std::int64_t>(m->id),
                            ros_conversions::ToSeconds(m->header.stamp),
                            ros_conversions::FromPoseMessage(m->pose));
      });
  update_subscriber_ = node.subscribe<stereo_fabmap_slam::KeyframeUpdate>(
      "keyframe_updates", 100, [this](const stereo_fabmap_slam::KeyframeUpdateConstPtr& m) {
        const pipeline::MappedKeyframe mapped = ros_conversions::FromMappedKeyframeMessage(*m);
        std::lock_guard<std::mutex> lock(mutex_);
        record_.ApplyUpdate(mapped.update);
      });
  place_subscriber_ = node.subscribe<stereo_fabmap_slam::PlaceResult>(
      "place_results", 100, [this](const stereo_fabmap_slam::PlaceResultConstPtr& m) {
        pipeline::PlaceResult result = ros_conversions::FromPlaceResultMessage(*m);
        std::lock_guard<std::mutex> lock(mutex_);
        record_.AddPlaceResult(std::move(result));
      });
  graph_subscriber_ = node.subscribe<stereo_fabmap_slam::MapGraph>(
      "map_graph", 1, [this](const stereo_fabmap_slam::MapGraphConstPtr& m) {
        pipeline::MapSnapshot map = ros_conversions::FromMapGraphMessage(*m);
        std::lock_guard<std::mutex> lock(mutex_);
        map_ = std::move(map);
      });
  loaded_subscriber_ = node.subscribe<stereo_fabmap_slam::MapLoaded>(
      "map_loaded", 1, [this](const stereo_fabmap_slam::MapLoadedConstPtr& m) {
        try {  // the loaded keyframes' times, for keyframes.txt and loops.csv
          const map::SavedMap saved = map::LoadMapFile(m->path);
          std::lock_guard<std::mutex> lock(mutex_);
          for (const map::SavedKeyframe& keyframe : saved.keyframes) {
            record_.AddKeyframeTime(keyframe.keyframe.id, keyframe.keyframe.timestamp);
          }
          map_keyframes_loaded_ = saved.keyframes.size();
        } catch (const std::exception& error) {
          NODELET_WARN("map %s unreadable for the record: %s", m->path.c_str(), error.what());
        }
      });
  mode_subscriber_ =
      node.subscribe<std_msgs::String>("mode", 1, [this](const std_msgs::StringConstPtr& m) {
        std::lock_guard<std::mutex> lock(mutex_);
        mode_ = m->data;
      });
  NODELET_INFO("recording the run into %s (written when the graph shuts down)", output_.c_str());
}

void RecorderNodelet::Write() {
  if (output_.empty()) return;
  try {
    std::filesystem::create_directories(output_);
    pipeline::JsonObject summary;
    summary.AddString("sequence", std::filesystem::path(output_).filename().string());
    summary.AddString("mode", mode_);
    summary.Add("map_keyframes_loaded", map_keyframes_loaded_);
    summary.Add("pairs_received", static_cast<std::int64_t>(counts_.received));
    summary.Add("pairs_refused", static_cast<std::int64_t>(counts_.refused));
    summary.Add("pairs_skipped", static_cast<std::int64_t>(counts_.skipped));
    summary.Add("wall_time_s", last_wall_ - first_wall_);
    record_.Write(output_, loop_closing_ && map_ ? &*map_ : nullptr, &summary);
    std::FILE* file = std::fopen((output_ + "/summary.json").c_str(), "w");
    if (file == nullptr) throw std::runtime_error("cannot write " + output_ + "/summary.json");
    std::fputs(summary.Text().c_str(), file);
    std::fclose(file);
    NODELET_INFO("run written to %s: %zu frames", output_.c_str(), record_.frames().size());
  } catch (const std::exception& error) {
    NODELET_ERROR("run not written to %s: %s", output_.c_str(), error.what());
  }
}

}  // namespace stereo_fabmap_slam

PLUGINLIB_EXPORT_CLASS(stereo_fabmap_slam::RecorderNodelet, nodelet::Nodelet)
