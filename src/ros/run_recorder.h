#pragma once

// A run of the nodelet graph as run_dataset writes its runs (pipeline::RunRecord): fed the
// stages' messages, live (the Recorder nodelet, output:=DIR) or from a recorded bag
// (bag_to_run), it writes trajectory.txt, odometry.txt, keyframes.txt, loops.csv, timing.csv and
// summary.json. Not thread-safe: the Recorder nodelet holds a lock.

#include <cstddef>
#include <optional>
#include <string>

#include <std_msgs/String.h>
#include <stereo_fabmap_slam/Keyframe.h>
#include <stereo_fabmap_slam/KeyframeUpdate.h>
#include <stereo_fabmap_slam/MapGraph.h>
#include <stereo_fabmap_slam/MapLoaded.h>
#include <stereo_fabmap_slam/PlaceResult.h>
#include <stereo_fabmap_slam/TrackedFrame.h>

#include "stereo_fabmap_slam/pipeline/run_record.h"

namespace stereo_fabmap_slam::ros_wiring {

class RunRecorder {
 public:
  // `loop_closing`: false, the map trajectory is the odometry's, as run_dataset's without it.
  explicit RunRecorder(bool loop_closing) : loop_closing_(loop_closing) {}

  // `wall_time` [s]: when the message came, for the summary's wall time (0 from a bag).
  void OnTrackedFrame(const stereo_fabmap_slam::TrackedFrame& frame, double wall_time);
  void OnKeyframe(const stereo_fabmap_slam::Keyframe& keyframe);
  void OnUpdate(const stereo_fabmap_slam::KeyframeUpdate& update);
  void OnPlaceResult(const stereo_fabmap_slam::PlaceResult& result);
  void OnMapGraph(const stereo_fabmap_slam::MapGraph& graph);
  // Reads the loaded map's keyframe times from its file; a file it cannot read is said so
  // (returned) and its keyframes go without a time.
  std::string OnMapLoaded(const stereo_fabmap_slam::MapLoaded& loaded);
  void OnMode(const std_msgs::String& mode) { mode_ = mode.data; }

  // Writes the files into `directory` (made if missing); `name`: the summary's "sequence".
  // Throws for a file that cannot be written.
  void Write(const std::string& directory, const std::string& name) const;
  std::size_t frames() const { return record_.frames().size(); }

 private:
  bool loop_closing_;
  pipeline::RunRecord record_;
  std::optional<pipeline::MapSnapshot> map_;
  pipeline::InputCounts counts_;
  std::string mode_ = "mapping";
  std::size_t map_keyframes_loaded_ = 0;
  double first_wall_ = 0, last_wall_ = 0;
};

}  // namespace stereo_fabmap_slam::ros_wiring
