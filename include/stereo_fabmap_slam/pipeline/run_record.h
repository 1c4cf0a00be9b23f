#pragma once

#include <cstdint>
#include <map>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include <Eigen/Geometry>

#include "stereo_fabmap_slam/io/trajectory.h"
#include "stereo_fabmap_slam/map/keyframe_update.h"
#include "stereo_fabmap_slam/odometry/tracker.h"
#include "stereo_fabmap_slam/pipeline/frame_record.h"
#include "stereo_fabmap_slam/pipeline/input_monitor.h"
#include "stereo_fabmap_slam/pipeline/map_state.h"
#include "stereo_fabmap_slam/pipeline/place_stage.h"
#include "stereo_fabmap_slam/pipeline/slam_mode.h"
#include "stereo_fabmap_slam/pipeline/stereo_front_end.h"
#include "stereo_fabmap_slam/pipeline/tracking_stage.h"

namespace stereo_fabmap_slam::pipeline {

// An ordered JSON object (summary.json): numbers, booleans and strings, in the order added.
class JsonObject {
 public:
  void Add(const std::string& key, double value, int decimals = 3);
  void Add(const std::string& key, std::int64_t value);
  void Add(const std::string& key, int value) { Add(key, static_cast<std::int64_t>(value)); }
  void Add(const std::string& key, std::size_t value) {
    Add(key, static_cast<std::int64_t>(value));
  }
  // The shortest text that gives the number back (4, 2.5).
  void AddNumber(const std::string& key, double value);
  void AddBool(const std::string& key, bool value);
  void AddString(const std::string& key, const std::string& value);
  std::string Text() const;  // one line, with a newline

 private:
  std::vector<std::pair<std::string, std::string>> fields_;  // key, JSON text of the value
};

// What a run of the SLAM produced, kept frame by frame, so that the offline runner and the
// nodelet graph (output:=DIR) write the same files from the same records: every frame's pose
// relative to its keyframe, the keyframes' odometry poses as the bundle adjustment left them,
// every loop detection, and at the end the map's poses (MapState).
class RunRecord {
 public:
  void AddFrame(FrameRecord frame) { frames_.push_back(std::move(frame)); }
  // A keyframe as the tracker made it (odom), then the bundle adjustment's corrections (in
  // either order: a correction is always the newer pose).
  void AddKeyframe(std::int64_t id, double timestamp, const Eigen::Isometry3d& T_odom_camera);
  void ApplyUpdate(const map::KeyframeUpdate& update);
  // A keyframe of a loaded map (its time, for keyframes.txt and loops.csv).
  void AddKeyframeTime(std::int64_t id, double timestamp) { keyframe_times_[id] = timestamp; }
  void AddPlaceResult(PlaceResult result) { place_results_.push_back(std::move(result)); }
  // The mapping and place stages' times of frame `index` (its keyframe's bundle adjustment, pose
  // graph, loop detection), added when they ran after the frame was recorded (concurrent
  // mapping). Throws std::out_of_range for a frame not recorded.
  void AddMappingTimes(std::size_t index, double bundle_adjustment_ms, double pose_graph_ms,
                       double loop_detection_ms);

  const std::vector<FrameRecord>& frames() const { return frames_; }
  const std::vector<PlaceResult>& place_results() const { return place_results_; }
  std::size_t keyframes() const { return odometry_poses_.size(); }  // this run's
  double KeyframeTime(std::int64_t id) const { return keyframe_times_.at(id); }
  // The same, NaN for a keyframe whose time this record never had.
  double TimeOf(std::int64_t id) const;

  // Every frame's rectified left camera pose, through its keyframe's latest pose: in odom (the
  // bundle adjustment's, no loop closing), and in map (`map`'s, null: the odometry's). The map
  // trajectory holds the frames that have a pose in the map: not those of a segment never found
  // in it; in localization mode, the frames' T_map_camera.
  io::Trajectory OdometryTrajectory() const;
  io::Trajectory MapTrajectory(const MapState* map) const;
  // Keyframes: the map's (loaded ones too), or without a map this run's odometry poses.
  io::Trajectory KeyframeTrajectory(const MapState* map) const;

  // Writes trajectory.txt, odometry.txt, keyframes.txt, loops.csv and timing.csv into
  // `directory` (which must exist), and adds what they amount to to `summary`: frames, frames
  // tracked, keyframes, per-stage times, loops, relocalizations. Throws io::FileError for a
  // file that cannot be written.
  void Write(const std::string& directory, const MapState* map, JsonObject* summary) const;

 private:
  std::vector<FrameRecord> frames_;
  std::map<std::int64_t, Eigen::Isometry3d> odometry_poses_;  // this run's keyframes, odom
  std::map<std::int64_t, double> keyframe_times_;
  std::vector<PlaceResult> place_results_;
};

}  // namespace stereo_fabmap_slam::pipeline
