#include "run_recorder.h"

#include <cstdio>
#include <filesystem>
#include <stdexcept>

#include "ros_conversions.h"
#include "stage_conversions.h"
#include "stereo_fabmap_slam/map/map_file.h"

namespace stereo_fabmap_slam::ros_wiring {

void RunRecorder::OnTrackedFrame(const stereo_fabmap_slam::TrackedFrame& frame, double wall_time) {
  if (wall_time > 0) {
    if (first_wall_ == 0) first_wall_ = wall_time;
    last_wall_ = wall_time;
  }
  counts_.received = frame.pairs_received;
  counts_.refused = frame.pairs_refused;
  counts_.skipped = frame.pairs_skipped;
  if (frame.tracked) {
    ++counts_.tracked;
    record_.AddFrame(ros_conversions::FromTrackedFrameMessage(frame));
  }
}

void RunRecorder::OnKeyframe(const stereo_fabmap_slam::Keyframe& keyframe) {
  record_.AddKeyframe(static_cast<std::int64_t>(keyframe.id),
                      ros_conversions::ToSeconds(keyframe.header.stamp),
                      ros_conversions::FromPoseMessage(keyframe.pose));
}

void RunRecorder::OnUpdate(const stereo_fabmap_slam::KeyframeUpdate& update) {
  record_.ApplyUpdate(ros_conversions::FromMappedKeyframeMessage(update).update);
}

void RunRecorder::OnPlaceResult(const stereo_fabmap_slam::PlaceResult& result) {
  record_.AddPlaceResult(ros_conversions::FromPlaceResultMessage(result));
}

void RunRecorder::OnMapGraph(const stereo_fabmap_slam::MapGraph& graph) {
  map_ = ros_conversions::FromMapGraphMessage(graph);
}

std::string RunRecorder::OnMapLoaded(const stereo_fabmap_slam::MapLoaded& loaded) {
  try {
    const map::SavedMap saved = map::LoadMapFile(loaded.path);
    for (const map::SavedKeyframe& keyframe : saved.keyframes) {
      record_.AddKeyframeTime(keyframe.keyframe.id, keyframe.keyframe.timestamp);
    }
    map_keyframes_loaded_ = saved.keyframes.size();
    return "";
  } catch (const std::exception& error) {
    map_keyframes_loaded_ = loaded.keyframes;
    return "map " + loaded.path + " unreadable for the record: " + error.what();
  }
}

void RunRecorder::Write(const std::string& directory, const std::string& name) const {
  std::filesystem::create_directories(directory);
  pipeline::JsonObject summary;
  summary.AddString("sequence", name);
  summary.AddString("mode", mode_);
  summary.Add("map_keyframes_loaded", map_keyframes_loaded_);
  summary.Add("pairs_received", static_cast<std::int64_t>(counts_.received));
  summary.Add("pairs_refused", static_cast<std::int64_t>(counts_.refused));
  summary.Add("pairs_skipped", static_cast<std::int64_t>(counts_.skipped));
  summary.Add("wall_time_s", last_wall_ - first_wall_);
  record_.Write(directory, loop_closing_ && map_ ? &*map_ : nullptr, &summary);
  const std::string path = directory + "/summary.json";
  std::FILE* file = std::fopen(path.c_str(), "w");
  if (file == nullptr) throw std::runtime_error("cannot write " + path);
  std::fputs(summary.Text().c_str(), file);
  if (std::fclose(file) != 0) throw std::runtime_error("cannot write " + path);
}

}  // namespace stereo_fabmap_slam::ros_wiring
