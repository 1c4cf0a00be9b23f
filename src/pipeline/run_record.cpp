#include "stereo_fabmap_slam/pipeline/run_record.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <memory>
#include <numeric>

#include "stereo_fabmap_slam/io/input_error.h"
#include "stereo_fabmap_slam/io/trajectory_file.h"

namespace stereo_fabmap_slam::pipeline {
namespace {

struct FileCloser {
  void operator()(std::FILE* file) const { std::fclose(file); }
};
using File = std::unique_ptr<std::FILE, FileCloser>;

File OpenForWriting(const std::string& path) {
  File file(std::fopen(path.c_str(), "w"));
  if (!file) throw io::FileError(path, 0, "cannot open file for writing");
  return file;
}

void FinishWriting(File file, const std::string& path) {
  if (std::ferror(file.get()) || std::fclose(file.release()) != 0) {
    throw io::FileError(path, 0, "write error");
  }
}

struct Stats {
  double median = 0, mean = 0;
};

Stats Summarise(std::vector<double> values) {
  Stats stats;
  if (values.empty()) return stats;
  stats.mean = std::accumulate(values.begin(), values.end(), 0.0) / values.size();
  std::nth_element(values.begin(), values.begin() + values.size() / 2, values.end());
  stats.median = values[values.size() / 2];
  return stats;
}

std::string Quoted(const std::string& text) {
  std::string quoted = "\"";
  for (const char c : text) {
    if (c == '"' || c == '\\') quoted += '\\';
    quoted += c;
  }
  return quoted + "\"";
}

}  // namespace

void JsonObject::Add(const std::string& key, double value, int decimals) {
  char text[64];
  std::snprintf(text, sizeof(text), "%.*f", decimals, value);
  fields_.emplace_back(key, text);
}

void JsonObject::Add(const std::string& key, std::int64_t value) {
  fields_.emplace_back(key, std::to_string(value));
}

void JsonObject::AddNumber(const std::string& key, double value) {
  char text[64];
  std::snprintf(text, sizeof(text), "%.10g", value);
  fields_.emplace_back(key, text);
}

void JsonObject::AddBool(const std::string& key, bool value) {
  fields_.emplace_back(key, value ? "true" : "false");
}

void JsonObject::AddString(const std::string& key, const std::string& value) {
  fields_.emplace_back(key, Quoted(value));
}

std::string JsonObject::Text() const {
  std::string text = "{";
  for (std::size_t i = 0; i < fields_.size(); ++i) {
    text += (i > 0 ? ", " : "") + Quoted(fields_[i].first) + ": " + fields_[i].second;
  }
  return text + "}\n";
}

void RunRecord::AddMappingTimes(std::size_t index, double bundle_adjustment_ms,
                                double pose_graph_ms, double loop_detection_ms) {
  FrameTiming& timing = frames_.at(index).timing;
  timing.bundle_adjustment_ms += bundle_adjustment_ms;
  timing.pose_graph_ms += pose_graph_ms;
  timing.loop_detection_ms += loop_detection_ms;
}

void RunRecord::AddKeyframe(std::int64_t id, double timestamp,
                            const Eigen::Isometry3d& T_odom_camera) {
  // An update can only follow its keyframe; one that reached this record first (the graph's
  // topics keep no order between them) is the newer pose.
  odometry_poses_.emplace(id, T_odom_camera);
  keyframe_times_[id] = timestamp;
}

void RunRecord::ApplyUpdate(const map::KeyframeUpdate& update) {
  for (const auto& [id, pose] : update.keyframe_poses) odometry_poses_[id] = pose;
}

double RunRecord::TimeOf(std::int64_t id) const {
  const auto time = keyframe_times_.find(id);
  return time == keyframe_times_.end() ? std::nan("") : time->second;
}

io::Trajectory RunRecord::OdometryTrajectory() const {
  io::Trajectory trajectory;
  for (const FrameRecord& frame : frames_) {
    // A lost frame without a keyframe to refer to has no pose, only the motion model's guess.
    if (frame.state == odometry::TrackingState::kLost && frame.reference_keyframe < 0) continue;
    const auto keyframe = odometry_poses_.find(frame.reference_keyframe);
    trajectory.push_back({frame.timestamp, keyframe == odometry_poses_.end()
                                               ? frame.T_world_camera
                                               : keyframe->second * frame.T_keyframe_camera});
  }
  return trajectory;
}

io::Trajectory RunRecord::MapTrajectory(const MapState* map) const {
  if (map == nullptr) return OdometryTrajectory();
  io::Trajectory trajectory;
  for (const FrameRecord& frame : frames_) {
    if (frame.T_map_camera) {
      trajectory.push_back({frame.timestamp, *frame.T_map_camera});  // localization mode
    } else if (frame.reference_keyframe >= 0 && map->InMap(frame.reference_keyframe)) {
      trajectory.push_back(
          {frame.timestamp, map->MapPose(frame.reference_keyframe) * frame.T_keyframe_camera});
    }
  }
  return trajectory;
}

io::Trajectory RunRecord::KeyframeTrajectory(const MapState* map) const {
  io::Trajectory trajectory;
  const std::map<std::int64_t, Eigen::Isometry3d> poses =
      map != nullptr ? map->MapPoses() : odometry_poses_;
  for (const auto& [id, pose] : poses) {
    // A keyframe whose time never reached this record (a recorder started late) is left out.
    const auto time = keyframe_times_.find(id);
    if (time != keyframe_times_.end()) trajectory.push_back({time->second, pose});
  }
  return trajectory;
}

void RunRecord::Write(const std::string& directory, const MapState* map,
                      JsonObject* summary) const {
  const io::Trajectory trajectory = MapTrajectory(map);
  io::WriteTumTrajectory(trajectory, directory + "/trajectory.txt");
  io::WriteTumTrajectory(OdometryTrajectory(), directory + "/odometry.txt");
  io::WriteTumTrajectory(KeyframeTrajectory(map), directory + "/keyframes.txt");

  // loops.csv: one row per verified candidate; times in seconds as in the trajectory files.
  const std::string loops_path = directory + "/loops.csv";
  File loops = OpenForWriting(loops_path);
  std::fprintf(loops.get(),
               "query_keyframe,query_time,match_keyframe,match_time,probability,inliers,accepted,"
               "reason\n");
  int accepted = 0, rejected = 0;
  std::vector<double> detection_ms;
  for (const PlaceResult& result : place_results_) {
    detection_ms.push_back(result.detection_ms);
    for (const place_recognition::LoopCandidate& c : result.detection.candidates) {
      if (!c.verified) continue;
      std::fprintf(loops.get(), "%ld,%.9f,%ld,%.9f,%.6f,%d,%d,\"%s\"\n",
                   static_cast<long>(result.keyframe_id), result.timestamp,
                   static_cast<long>(c.keyframe_id), TimeOf(c.keyframe_id), c.probability,
                   c.inliers, c.accepted ? 1 : 0, c.reason.c_str());
      ++(c.accepted ? accepted : rejected);
    }
  }
  FinishWriting(std::move(loops), loops_path);

  const std::string timing_path = directory + "/timing.csv";
  File timing = OpenForWriting(timing_path);
  std::fprintf(timing.get(),
               "frame,timestamp,state,keyframe,rectification_ms,detection_ms,description_ms,"
               "stereo_ms,tracking_ms,bundle_adjustment_ms,place_description_ms,"
               "loop_detection_ms,pose_graph_ms,relocalization_ms,inliers,on_map,relocalization,"
               "note\n");
  std::vector<double> stage[7], relocalization_ms;
  int tracked = 0, keyframes = 0, relocalizations = 0, attempts = 0, frames_lost = 0;
  double pose_graph_ms_max = 0;
  for (std::size_t i = 0; i < frames_.size(); ++i) {
    const FrameRecord& f = frames_[i];
    const FrameTiming& t = f.timing;
    std::fprintf(timing.get(),
                 "%zu,%.9f,%s,%d,%.3f,%.3f,%.3f,%.3f,%.3f,%.3f,%.3f,%.3f,%.3f,%.3f,%d,%d,\"%s\","
                 "\"%s\"\n",
                 i, f.timestamp, odometry::TrackingStateName(f.state), f.is_keyframe ? 1 : 0,
                 t.rectification_ms, t.detection_ms, t.description_ms, t.stereo_ms, t.tracking_ms,
                 t.bundle_adjustment_ms, t.place_description_ms, t.loop_detection_ms,
                 t.pose_graph_ms, t.relocalization_ms, f.inliers, f.on_map ? 1 : 0,
                 f.relocalization.value_or("").c_str(), f.note.c_str());
    tracked += f.state != odometry::TrackingState::kLost ? 1 : 0;
    keyframes += f.is_keyframe ? 1 : 0;
    frames_lost += f.on_map ? 0 : 1;
    pose_graph_ms_max = std::max(pose_graph_ms_max, t.pose_graph_ms);
    const double values[7] = {t.rectification_ms, t.detection_ms, t.description_ms,
                              t.stereo_ms,        t.tracking_ms,  t.bundle_adjustment_ms,
                              t.TrackingTotal()};
    for (int k = 0; k < 7; ++k) stage[k].push_back(values[k]);
    if (f.relocalization) {
      ++attempts;
      relocalizations += f.relocalized ? 1 : 0;
      relocalization_ms.push_back(t.relocalization_ms);
    }
  }
  FinishWriting(std::move(timing), timing_path);

  summary->Add("frames", frames_.size());
  summary->Add("frames_tracked", tracked);
  summary->Add("keyframes", keyframes);
  summary->Add("map_keyframes", map != nullptr ? map->MapPoses().size() : std::size_t{0});
  const char* names[7] = {"rectification", "detection",         "description",   "stereo",
                          "tracking",      "bundle_adjustment", "tracking_total"};
  for (int k = 0; k < 7; ++k) {
    const Stats s = Summarise(stage[k]);
    summary->Add(std::string(names[k]) + "_ms_median", s.median);
    summary->Add(std::string(names[k]) + "_ms_mean", s.mean);
  }
  summary->AddBool("loop_closing", map != nullptr);
  summary->Add("loops_accepted", accepted);
  summary->Add("loops_rejected", rejected);
  summary->Add("loop_detection_ms_median", Summarise(detection_ms).median);
  summary->Add("pose_graph_ms_max", pose_graph_ms_max);
  summary->Add("relocalizations", relocalizations);
  summary->Add("relocalization_attempts", attempts);
  summary->Add("frames_lost", frames_lost);
  summary->Add("relocalization_ms_median", Summarise(relocalization_ms).median);
  summary->Add("trajectory_frames", trajectory.size());
}

}  // namespace stereo_fabmap_slam::pipeline
