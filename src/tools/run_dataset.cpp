// Runs the SLAM offline on an EuRoC ASL sequence, in one thread and deterministically (or with
// --threads the mapping beside the tracking, as the nodelet graph runs it), and writes
// trajectory.txt, keyframes.txt, timing.csv and summary.json.
#include <dlfcn.h>
#include <sys/resource.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <exception>
#include <filesystem>
#include <iostream>
#include <map>
#include <memory>
#include <numeric>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include "command_line.h"
#include "dense_run.h"
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
    "                   [--every N] [--output DIR] [--dense] [--threads] [--quiet]\n"
    "Runs the stereo SLAM on an EuRoC sequence and writes to DIR (default output/<name>):\n"
    "  trajectory.txt  TUM, rectified left camera in the map frame (after loop closing), every "
    "frame\n"
    "  odometry.txt    TUM, the same from the odometry alone (no loop closing)\n"
    "  keyframes.txt   TUM, keyframes in the map frame after the last optimisation\n"
    "  loops.csv       every verified loop candidate, accepted or not, with the reason\n"
    "  timing.csv      milliseconds per frame and stage\n"
    "  summary.json    counts, times, and ATE against ground truth when the sequence has it\n"
    "  mesh.ply, dense_cloud.ply  with --dense: every keyframe's stereo depth fused at its map\n"
    "                  pose during the run and again where the map moved it, as the DenseMapper\n"
    "                  does (sections dense_depth, dense_fusion, dense_mapping of the config)\n"
    "--load-map starts from a map saved by --save-map (same vocabulary and camera); with\n"
    "--mode localization it is used without being extended: the camera is relocalized in it at\n"
    "start, after every loss and at each keyframe, and trajectory.txt is in the map's frame.\n"
    "--every N processes every Nth stereo pair only, as a tracker that cannot keep up with a\n"
    "camera (or a bag played N times faster) sees them; default 1. N may be fractional: 2.5\n"
    "processes pairs 0, 2, 5, 7, 10, ..., as a tracker at 25 ms a pair sees a bag at 5x.\n"
    "--threads maps keyframes (bundle adjustment, pose graph, loop detection) on a second thread\n"
    "while tracking goes on, as the nodelet graph does, and with --dense fuses the dense map on\n"
    "a third thread below their priority, as the DenseMapper does (the keyframes wait for it,\n"
    "and what it has not fused when the run ends is fused then): faster, but the result\n"
    "depends on timing.\n"
    "Without it the run is in one thread, in order, and the same input gives the same output.\n"
    "Default configs: " STEREO_FABMAP_SLAM_CONFIG_DIR "/euroc.yaml, " STEREO_FABMAP_SLAM_CONFIG_DIR
    "/fabmap.yaml\n";

double NowMs() {
  return std::chrono::duration<double, std::milli>(
             std::chrono::steady_clock::now().time_since_epoch())
      .count();
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

// Loads the dense mapping library (dense_run.h) and makes its DenseRun; the library stays loaded
// until the process ends. Looked up as the dynamic linker finds libraries (this program's run
// path: the build's or the install's lib directory), then beside this program's directory.
std::unique_ptr<tools::DenseRun> LoadDenseRun(const tools::SlamConfiguration& options,
                                              const camera::StereoRectifier& rectifier,
                                              bool concurrent, bool quiet) {
  void* library = dlopen(tools::kDenseRunLibrary, RTLD_NOW | RTLD_LOCAL);
  std::string error = library == nullptr ? dlerror() : "";
  if (library == nullptr) {
    const std::filesystem::path beside =
        std::filesystem::read_symlink("/proc/self/exe").parent_path().parent_path() /
        tools::kDenseRunLibrary;
    library = dlopen(beside.c_str(), RTLD_NOW | RTLD_LOCAL);
    if (library == nullptr) error += "; " + std::string(dlerror());
  }
  if (library == nullptr) throw std::runtime_error("--dense: cannot load the dense map: " + error);
  const auto create =
      reinterpret_cast<tools::CreateDenseRunFunction>(dlsym(library, tools::kCreateDenseRunSymbol));
  if (create == nullptr) {
    throw std::runtime_error("--dense: " + std::string(tools::kDenseRunLibrary) + " has no " +
                             tools::kCreateDenseRunSymbol);
  }
  return std::unique_ptr<tools::DenseRun>(create(options.dense_mapping, options.dense_depth,
                                                 options.dense_fusion, rectifier, concurrent,
                                                 quiet));
}

}  // namespace

int main(int argc, char** argv) {
  std::optional<tools::CommandLine> args;
  double every = 1;
  try {
    args.emplace(argc, argv,
                 std::set<std::string>{"config", "fabmap-config", "output", "load-map", "save-map",
                                       "mode", "every"},
                 std::set<std::string>{"quiet", "help", "no-loop-closing", "dense", "threads"});
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
      if (load_map) {
        const pipeline::MapFileAnswer loaded = slam.LoadMap(*load_map);
        if (!loaded.success) throw std::runtime_error("--load-map: " + loaded.message);
        if (!quiet) std::printf("%s\n", loaded.message.c_str());
      }
      slam.SetMode(mode);
    }
    if (args->Flag("threads")) slam.EnableConcurrentMapping();
    const std::size_t loaded_keyframes = slam.mapping().pose_graph().size();
    std::unique_ptr<tools::DenseRun> dense_run;
    if (args->Flag("dense"))
      dense_run = LoadDenseRun(options, rectifier, args->Flag("threads"), quiet);
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
      const pipeline::FrameRecord* frame =
          slam.ProcessFrame(images.timestamp_ns * 1e-9, images.left, images.right, skipped);
      processing_ms += NowMs() - start;
      if (dense_run) dense_run->AfterFrame(images, frame, slam);
      // What the input monitor found (a gap, a frozen or wrongly sized image...).
      for (const pipeline::InputEvent& event : slam.last_input_events()) {
        if (!quiet)
          std::printf("frame %zu/%zu: %s\n", i + 1, sequence.size(), event.message.c_str());
      }
      if (!quiet && frame != nullptr &&
          (frame->state == odometry::TrackingState::kLost || processed % 100 == 0)) {
        std::printf("frame %zu/%zu: %s, %zu keyframes, resident %.1f MB\n", i + 1, sequence.size(),
                    odometry::TrackingStateName(frame->state), slam.keyframe_count(),
                    ResidentMegabytes());
      }
    }
    {  // the keyframes still being mapped (concurrent mapping) are part of the processing
      const double start = NowMs();
      slam.Synchronize();
      if (place_options && options.global_refinement.at_end) {
        const backend::GlobalRefinementSummary refined = slam.RefineMap(options.global_refinement);
        if (!quiet) {
          std::printf(
              "Global refinement: %zu keyframes, %zu points, %zu observations, %zu edges, "
              "%d iterations, cost %.1f -> %.1f, %.0f ms\n",
              refined.keyframes, refined.points, refined.observations, refined.edges,
              refined.iterations, refined.initial_cost, refined.final_cost, NowMs() - start);
        }
      }
      processing_ms += NowMs() - start;
    }
    const double wall_s = (NowMs() - wall_start) / 1000.0;
    const double cpu_s = CpuSeconds() - cpu_start;
    if (save_map) {
      const pipeline::MapFileAnswer saved = slam.SaveMap(*save_map);
      if (!saved.success) throw std::runtime_error("--save-map: " + saved.message);
      if (!quiet) std::printf("%s\n", saved.message.c_str());
    }

    const io::Trajectory trajectory = slam.MapTrajectory();
    const io::Trajectory odometry_trajectory = slam.OdometryTrajectory();
    const double duration =
        sequence.size() > 1
            ? (sequence.frames().back().timestamp_ns - sequence.frames().front().timestamp_ns) *
                      1e-9 +
                  0.05
            : 0.05;
    pipeline::JsonObject summary;
    summary.AddString("sequence", name);
    summary.AddNumber("every", every);
    summary.AddString("mode", pipeline::SlamModeName(mode));
    summary.Add("map_keyframes_loaded", loaded_keyframes);
    summary.Add("wall_time_s", wall_s);
    summary.Add("processing_time_s", processing_ms / 1000.0);
    summary.Add("cpu_time_s", cpu_s);
    summary.Add("realtime_factor", duration / (processing_ms / 1000.0));
    summary.Add("peak_rss_mb", PeakResidentMegabytes(), 1);
    summary.Add("global_refinements", slam.mapping().global_refinements());
    slam.record().Write(output, slam.map_state(), &summary);
    if (dense_run) {
      dense_run->Finish(slam);
      dense_run->Write(output, &summary);
    }
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
        summary.Add("ate_rmse_odometry", odometry_result->ate.rmse, 6);
      }
    }
    const std::optional<evaluation::EvaluationResult> evaluated =
        sequence.has_ground_truth() ? evaluate(trajectory) : std::nullopt;
    if (sequence.has_ground_truth() && !evaluated) {
      summary.Add("ate_matched", 0);
      summary.AddString("ate_note", "the ATE needs at least 3 poses matched to the ground truth");
    } else if (evaluated) {
      const evaluation::EvaluationResult& result = *evaluated;
      const auto& est = result.aligned_estimate;
      const auto& ref = result.matched_reference;
      const Eigen::Vector3d est_move =
          est.back().pose.translation() - est.front().pose.translation();
      const Eigen::Vector3d ref_move =
          ref.back().pose.translation() - ref.front().pose.translation();
      summary.Add("ate_rmse", result.ate.rmse, 6);
      summary.Add("ate_max", result.ate.max, 6);
      summary.Add("ate_matched", result.matched);
      summary.Add("rpe_trans_rmse", result.rpe.translation.rmse, 6);
      summary.Add("displacement_estimate", est_move.norm(), 6);
      summary.Add("displacement_ground_truth", ref_move.norm(), 6);
      summary.Add("displacement_error", (est_move - ref_move).norm(), 6);
    }
    const std::string json = summary.Text();
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
