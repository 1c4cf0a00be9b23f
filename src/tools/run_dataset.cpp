// Runs the odometry offline on an EuRoC ASL sequence, in one thread and deterministically, and
// writes trajectory.txt, keyframes.txt, timing.csv and summary.json.
#include <sys/resource.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <exception>
#include <filesystem>
#include <iostream>
#include <numeric>
#include <optional>
#include <string>
#include <vector>

#include "command_line.h"
#include "slam_configuration.h"
#include "stereo_fabmap_slam/datasets/euroc_sequence.h"
#include "stereo_fabmap_slam/evaluation/trajectory_metrics.h"
#include "stereo_fabmap_slam/io/trajectory_file.h"
#include "stereo_fabmap_slam/pipeline/stereo_slam.h"

namespace {

using namespace stereo_fabmap_slam;  // NOLINT: a tool's main file

constexpr char kUsage[] =
    "usage: run_dataset ASL_DIR [--config FILE] [--fabmap-config FILE] [--no-loop-closing]\n"
    "                   [--load-map FILE] [--mode mapping|localization] [--save-map FILE]\n"
    "                   [--every N] [--output DIR] [--quiet]\n"
    "Runs the stereo SLAM on an EuRoC sequence and writes to DIR (default output/<name>):\n"
    "  trajectory.txt  TUM, rectified left camera in the map frame (after loop closing), every "
    "frame\n"
    "  odometry.txt    TUM, the same from the odometry alone (no loop closing)\n"
    "  keyframes.txt   TUM, keyframes in the map frame after the last optimisation\n"
    "  loops.csv       every verified loop candidate, accepted or not, with the reason\n"
    "  timing.csv      milliseconds per frame and stage\n"
    "  summary.json    counts, times, and ATE against ground truth when the sequence has it\n"
    "--load-map starts from a map saved by --save-map (same vocabulary and camera); with\n"
    "--mode localization it is used without being extended: the camera is relocalized in it at\n"
    "start, after every loss and at each keyframe, and trajectory.txt is in the map's frame.\n"
    "--every N processes every Nth stereo pair only, as a tracker that cannot keep up with a\n"
    "camera (or a bag played N times faster) sees them; default 1. N may be fractional: 2.5\n"
    "processes pairs 0, 2, 5, 7, 10, ..., as a tracker at 25 ms a pair sees a bag at 5x.\n"
    "Default configs: " STEREO_FABMAP_SLAM_CONFIG_DIR "/euroc.yaml, " STEREO_FABMAP_SLAM_CONFIG_DIR
    "/fabmap.yaml\n";

double NowMs() {
  return std::chrono::duration<double, std::milli>(
             std::chrono::steady_clock::now().time_since_epoch())
      .count();
}

// `every` as summary.json gives it: 4, or 2.5.
std::string EveryText(double every) {
  char text[32];
  std::snprintf(text, sizeof(text), "%g", every);
  return text;
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

double CpuSeconds() {
  rusage usage{};
  getrusage(RUSAGE_SELF, &usage);
  return usage.ru_utime.tv_sec + usage.ru_stime.tv_sec +
         1e-6 * (usage.ru_utime.tv_usec + usage.ru_stime.tv_usec);
}

// The memory in use now (not the peak): for memory growth over a long run.
double ResidentMegabytes() {
  std::size_t pages = 0, resident = 0;
  std::FILE* statm = std::fopen("/proc/self/statm", "r");
  if (statm == nullptr) return 0;
  if (std::fscanf(statm, "%zu %zu", &pages, &resident) != 2) resident = 0;
  std::fclose(statm);
  return static_cast<double>(resident) * static_cast<double>(sysconf(_SC_PAGESIZE)) / 1048576.0;
}

double PeakResidentMegabytes() {
  rusage usage{};
  getrusage(RUSAGE_SELF, &usage);
  return usage.ru_maxrss / 1024.0;  // kilobytes on Linux
}

struct LoopCounts {
  int accepted = 0, rejected = 0;
  std::vector<double> detection_ms;  // per keyframe
  double pose_graph_ms_max = 0;
};

// One row per verified candidate; times in seconds as in the trajectory files.
LoopCounts WriteLoops(const pipeline::StereoSlam& slam, const std::string& path) {
  std::FILE* file = std::fopen(path.c_str(), "w");
  if (file == nullptr) throw std::runtime_error("cannot write " + path);
  std::fprintf(file,
               "query_keyframe,query_time,match_keyframe,match_time,probability,inliers,accepted,"
               "reason\n");
  LoopCounts counts;
  for (const pipeline::FrameRecord& frame : slam.frames()) {
    if (!frame.loop_detection) continue;
    counts.detection_ms.push_back(frame.timing.loop_detection_ms);
    counts.pose_graph_ms_max = std::max(counts.pose_graph_ms_max, frame.timing.pose_graph_ms);
    for (const place_recognition::LoopCandidate& c : frame.loop_detection->candidates) {
      if (!c.verified) continue;
      std::fprintf(file, "%ld,%.9f,%ld,%.9f,%.6f,%d,%d,\"%s\"\n",
                   static_cast<long>(frame.loop_detection->query_id), frame.timestamp,
                   static_cast<long>(c.keyframe_id), slam.KeyframeTime(c.keyframe_id),
                   c.probability, c.inliers, c.accepted ? 1 : 0, c.reason.c_str());
      ++(c.accepted ? counts.accepted : counts.rejected);
    }
  }
  std::fclose(file);
  return counts;
}

void WriteTiming(const std::vector<pipeline::FrameRecord>& frames, const std::string& path) {
  std::FILE* file = std::fopen(path.c_str(), "w");
  if (file == nullptr) throw std::runtime_error("cannot write " + path);
  std::fprintf(file,
               "frame,timestamp,state,keyframe,rectification_ms,detection_ms,description_ms,"
               "stereo_ms,tracking_ms,bundle_adjustment_ms,place_description_ms,"
               "loop_detection_ms,pose_graph_ms,relocalization_ms,inliers,on_map,relocalization,"
               "note\n");
  for (std::size_t i = 0; i < frames.size(); ++i) {
    const pipeline::FrameRecord& f = frames[i];
    const pipeline::FrameTiming& t = f.timing;
    // The relocalization attempt of the frame, if any: its outcome, keyframe and inliers.
    std::string relocalization;
    if (f.relocalization) {
      const relocalization::Relocalization& r = f.relocalization->result;
      relocalization = std::string(relocalization::RelocalizationStatusName(r.status)) +
                       (r.keyframe_id >= 0 ? " against keyframe " + std::to_string(r.keyframe_id)
                                           : std::string()) +
                       ": " + r.reason;
    }
    std::fprintf(file,
                 "%zu,%.9f,%s,%d,%.3f,%.3f,%.3f,%.3f,%.3f,%.3f,%.3f,%.3f,%.3f,%.3f,%d,%d,\"%s\","
                 "\"%s\"\n",
                 i, f.timestamp, odometry::TrackingStateName(f.state), f.is_keyframe ? 1 : 0,
                 t.rectification_ms, t.detection_ms, t.description_ms, t.stereo_ms, t.tracking_ms,
                 t.bundle_adjustment_ms, t.place_description_ms, t.loop_detection_ms,
                 t.pose_graph_ms, t.relocalization_ms, f.inliers, f.on_map ? 1 : 0,
                 relocalization.c_str(), f.note.c_str());
  }
  std::fclose(file);
}

}  // namespace

int main(int argc, char** argv) {
  std::optional<tools::CommandLine> args;
  double every = 1;
  try {
    args.emplace(argc, argv,
                 std::set<std::string>{"config", "fabmap-config", "output", "load-map", "save-map",
                                       "mode", "every"},
                 std::set<std::string>{"quiet", "help", "no-loop-closing"});
    if (args->Flag("help")) {
      std::fputs(kUsage, stdout);
      return 0;
    }
    if (args->positional().size() != 1) throw std::invalid_argument("expected one ASL_DIR");
    every = args->NumberOr("every", 1);
    // A million pairs is 14 hours at 20 Hz: beyond any sequence, and a bound the cast can take.
    if (!(every >= 1 && every <= 1e6)) {
      throw std::invalid_argument("--every is a number of pairs, 1 to 1000000");
    }
  } catch (const std::invalid_argument& error) {
    std::fprintf(stderr, "run_dataset: %s\n%s", error.what(), kUsage);
    return 2;
  }
  try {
    const std::string asl = args->positional()[0];
    const std::string config = args->ValueOr("config", STEREO_FABMAP_SLAM_CONFIG_DIR "/euroc.yaml");
    const std::string name = std::filesystem::path(asl).filename().empty()
                                 ? std::filesystem::path(asl).parent_path().filename().string()
                                 : std::filesystem::path(asl).filename().string();
    const std::string output = args->ValueOr("output", "output/" + name);
    const bool quiet = args->Flag("quiet");

    tools::SlamConfiguration options = tools::SlamConfiguration::Load(config);
    const bool loop_closing = !args->Flag("no-loop-closing");
    const std::optional<std::string> load_map = args->Value("load-map");
    const std::optional<std::string> save_map = args->Value("save-map");
    pipeline::SlamMode mode = pipeline::SlamMode::kMapping;
    if (const std::optional<std::string> name = args->Value("mode")) {
      bool known = false;
      for (const auto& entry : pipeline::kSlamModeNames) {
        if (*name == entry.name) {
          mode = entry.value;
          known = true;
        }
      }
      if (!known) throw std::invalid_argument("--mode is mapping or localization");
    }
    if (!loop_closing && (load_map || save_map || mode == pipeline::SlamMode::kLocalization)) {
      throw std::invalid_argument(
          "maps and localization need loop closing's keyframe map: drop --no-loop-closing");
    }
    if (mode == pipeline::SlamMode::kLocalization && !load_map) {
      throw std::invalid_argument("--mode localization needs a map (--load-map FILE)");
    }
    const std::string fabmap_config =
        args->ValueOr("fabmap-config", STEREO_FABMAP_SLAM_CONFIG_DIR "/fabmap.yaml");
    std::optional<place_recognition::PlaceRecognitionOptions> place_options;
    if (loop_closing) {
      place_options = options.LoadPlaceRecognition(fabmap_config);
    }
    const datasets::EurocSequence sequence = datasets::EurocSequence::Open(asl);
    const camera::StereoRectifier rectifier =
        camera::StereoRectifier::FromCalibration(sequence.calibration(), options.rectification);
    if (!quiet) {
      std::cout << "config " << config << "\n";
      options.Print(std::cout);
      std::cout << "sequence " << asl << ": " << sequence.size() << " stereo pairs\n";
    }
    for (const datasets::UnpairedImage& image : sequence.unpaired()) {
      std::fprintf(stderr, "warning: %s image %s has no partner, skipped\n", image.camera.c_str(),
                   image.path.c_str());
    }
    std::filesystem::create_directories(output);

    pipeline::StereoSlam slam(options.front_end, options.bundle_adjustment, rectifier, NowMs);
    if (loop_closing) {
      options.EnableLoopClosing(*place_options, rectifier, &slam);
      if (load_map) slam.LoadMap(*load_map);
      slam.SetMode(mode);
    }
    const std::size_t loaded_keyframes = slam.map() ? slam.map()->pose_graph().size() : 0;
    const double cpu_start = CpuSeconds();
    double processing_ms = 0;  // excludes reading images from disk
    const double wall_start = NowMs();
    std::size_t processed = 0;
    // Pair floor(k * every) for k = 0, 1, ...: a fractional `every` skips a varying number of
    // pairs, as a tracker slower than the camera by a fraction does (FrameQueue).
    for (std::size_t k = 0, i = 0, previous = 0; i < sequence.size();
         previous = i, ++k, i = static_cast<std::size_t>(std::floor(k * every + 1e-9))) {
      ++processed;
      const datasets::StereoImages images = sequence.LoadStereoPair(i);
      const double start = NowMs();
      const int skipped = i == 0 ? 0 : static_cast<int>(i - previous) - 1;
      const pipeline::FrameRecord& frame =
          slam.ProcessFrame(images.timestamp_ns * 1e-9, images.left, images.right, skipped);
      processing_ms += NowMs() - start;
      if (!quiet && (frame.state == odometry::TrackingState::kLost || processed % 100 == 0)) {
        std::printf("frame %zu/%zu: %s, %zu keyframes, resident %.1f MB\n", i + 1, sequence.size(),
                    odometry::TrackingStateName(frame.state), slam.keyframe_count(),
                    ResidentMegabytes());
      }
    }
    const double wall_s = (NowMs() - wall_start) / 1000.0;
    const double cpu_s = CpuSeconds() - cpu_start;
    if (save_map) slam.SaveMap(*save_map);

    const evaluation::Trajectory trajectory = slam.MapTrajectory();
    const evaluation::Trajectory odometry_trajectory = slam.OdometryTrajectory();
    io::WriteTumTrajectory(trajectory, output + "/trajectory.txt");
    io::WriteTumTrajectory(odometry_trajectory, output + "/odometry.txt");
    const LoopCounts loops = WriteLoops(slam, output + "/loops.csv");
    io::WriteTumTrajectory(slam.KeyframeTrajectory(), output + "/keyframes.txt");
    WriteTiming(slam.frames(), output + "/timing.csv");

    std::vector<double> stage[7];
    int tracked = 0;
    for (const pipeline::FrameRecord& f : slam.frames()) {
      tracked += f.state != odometry::TrackingState::kLost ? 1 : 0;
      const pipeline::FrameTiming& t = f.timing;
      const double values[7] = {t.rectification_ms, t.detection_ms, t.description_ms,
                                t.stereo_ms,        t.tracking_ms,  t.bundle_adjustment_ms,
                                t.TrackingTotal()};
      for (int k = 0; k < 7; ++k) stage[k].push_back(values[k]);
    }
    const char* names[7] = {"rectification", "detection",         "description",   "stereo",
                            "tracking",      "bundle_adjustment", "tracking_total"};
    const double duration =
        sequence.size() > 1
            ? (sequence.frames().back().timestamp_ns - sequence.frames().front().timestamp_ns) *
                      1e-9 +
                  0.05
            : 0.05;
    const std::size_t keyframes = static_cast<std::size_t>(
        std::count_if(slam.frames().begin(), slam.frames().end(),
                      [](const pipeline::FrameRecord& f) { return f.is_keyframe; }));
    const std::size_t map_keyframes = slam.map() ? slam.map()->pose_graph().size() : 0;
    std::string json = "{\"sequence\": \"" + name + "\", \"frames\": " + std::to_string(processed) +
                       ", \"every\": " + EveryText(every) +
                       ", \"frames_tracked\": " + std::to_string(tracked) +
                       ", \"keyframes\": " + std::to_string(keyframes) + ", \"mode\": \"" +
                       (mode == pipeline::SlamMode::kMapping ? "mapping" : "localization") +
                       "\", \"map_keyframes_loaded\": " + std::to_string(loaded_keyframes) +
                       ", \"map_keyframes\": " + std::to_string(map_keyframes);
    char buffer[256];
    std::snprintf(buffer, sizeof(buffer),
                  ", \"wall_time_s\": %.3f, \"processing_time_s\": %.3f, \"cpu_time_s\": %.3f, "
                  "\"realtime_factor\": %.3f, \"peak_rss_mb\": %.1f",
                  wall_s, processing_ms / 1000.0, cpu_s, duration / (processing_ms / 1000.0),
                  PeakResidentMegabytes());
    json += buffer;
    for (int k = 0; k < 7; ++k) {
      const Stats s = Summarise(stage[k]);
      std::snprintf(buffer, sizeof(buffer), ", \"%s_ms_median\": %.3f, \"%s_ms_mean\": %.3f",
                    names[k], s.median, names[k], s.mean);
      json += buffer;
    }
    std::snprintf(buffer, sizeof(buffer),
                  ", \"loop_closing\": %s, \"loops_accepted\": %d, \"loops_rejected\": %d, "
                  "\"loop_detection_ms_median\": %.3f, \"pose_graph_ms_max\": %.3f",
                  loop_closing ? "true" : "false", loops.accepted, loops.rejected,
                  Summarise(loops.detection_ms).median, loops.pose_graph_ms_max);
    json += buffer;
    int relocalizations = 0, attempts = 0, frames_lost = 0;
    std::vector<double> relocalization_ms;
    for (const pipeline::FrameRecord& f : slam.frames()) {
      frames_lost += f.on_map ? 0 : 1;
      if (!f.relocalization) continue;
      ++attempts;
      relocalizations += f.relocalization->result.success() ? 1 : 0;
      relocalization_ms.push_back(f.relocalization->ms);
    }
    std::snprintf(buffer, sizeof(buffer),
                  ", \"relocalizations\": %d, \"relocalization_attempts\": %d, "
                  "\"frames_lost\": %d, \"relocalization_ms_median\": %.3f, "
                  "\"trajectory_frames\": %zu",
                  relocalizations, attempts, frames_lost, Summarise(relocalization_ms).median,
                  trajectory.size());
    json += buffer;
    // Ground truth is the body frame: move it to the rectified left camera we estimate. The ATE
    // needs 3 poses matched to it; with fewer (a sequence of one or two frames, a map that never
    // found the camera, ground truth that does not cover the images) the outputs are written all
    // the same and the summary says why there is no ATE.
    const evaluation::Trajectory truth =
        sequence.has_ground_truth()
            ? evaluation::TransformToSensorFrame(sequence.ground_truth(),
                                                 rectifier.T_body_rectified_left())
            : evaluation::Trajectory{};
    const auto evaluate =
        [&](const evaluation::Trajectory& estimate) -> std::optional<evaluation::EvaluationResult> {
      try {
        return evaluation::EvaluateTrajectory(truth, estimate, evaluation::EvaluationOptions{});
      } catch (const std::invalid_argument& error) {
        if (!quiet) std::fprintf(stderr, "run_dataset: no ATE: %s\n", error.what());
        return std::nullopt;
      }
    };
    if (sequence.has_ground_truth()) {
      if (const auto odometry_result = evaluate(odometry_trajectory)) {
        std::snprintf(buffer, sizeof(buffer), ", \"ate_rmse_odometry\": %.6f",
                      odometry_result->ate.rmse);
        json += buffer;
      }
    }
    const std::optional<evaluation::EvaluationResult> evaluated =
        sequence.has_ground_truth() ? evaluate(trajectory) : std::nullopt;
    if (sequence.has_ground_truth() && !evaluated) {
      json +=
          ", \"ate_matched\": 0, \"ate_note\": \"the ATE needs at least 3 poses matched to the "
          "ground truth\"";
    } else if (evaluated) {
      const evaluation::EvaluationResult& result = *evaluated;
      const auto& est = result.aligned_estimate;
      const auto& ref = result.matched_reference;
      const Eigen::Vector3d est_move =
          est.back().pose.translation() - est.front().pose.translation();
      const Eigen::Vector3d ref_move =
          ref.back().pose.translation() - ref.front().pose.translation();
      std::snprintf(buffer, sizeof(buffer),
                    ", \"ate_rmse\": %.6f, \"ate_max\": %.6f, \"ate_matched\": %zu, "
                    "\"rpe_trans_rmse\": %.6f, \"displacement_estimate\": %.6f, "
                    "\"displacement_ground_truth\": %.6f, \"displacement_error\": %.6f",
                    result.ate.rmse, result.ate.max, result.matched, result.rpe.translation.rmse,
                    est_move.norm(), ref_move.norm(), (est_move - ref_move).norm());
      json += buffer;
    }
    json += "}\n";
    std::FILE* file = std::fopen((output + "/summary.json").c_str(), "w");
    if (file == nullptr) throw std::runtime_error("cannot write " + output + "/summary.json");
    std::fputs(json.c_str(), file);
    std::fclose(file);
    std::fputs(json.c_str(), stdout);
  } catch (const std::exception& error) {
    std::fprintf(stderr, "run_dataset: %s\n", error.what());
    return 1;
  }
  return 0;
}
