// Relocalization figures for docs/benchmarks.md: maps an EuRoC-layout sequence (a rendered route
// or a real one) with the offline SLAM, then relocalizes frames against that map as the
// relocalize service does (no tracking, nothing changed) and prints the time per attempt, the
// share found, and the error of each found pose against ground truth, relative to the keyframe
// it was found against (the relocalizer's own error, not the map's drift).
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <exception>
#include <limits>
#include <optional>
#include <string>
#include <vector>

#include "command_line.h"
#include "slam_configuration.h"
#include "stereo_fabmap_slam/datasets/euroc_sequence.h"
#include "stereo_fabmap_slam/evaluation/pose_interpolation.h"
#include "stereo_fabmap_slam/evaluation/trajectory_metrics.h"
#include "stereo_fabmap_slam/pipeline/stereo_slam.h"

namespace {

using namespace stereo_fabmap_slam;  // NOLINT: a tool's main file

constexpr char kUsage[] =
    "usage: benchmark_relocalization ASL_DIR [--map-until S] [--from S] [--every N]\n"
    "                                [--config FILE] [--fabmap-config FILE]\n"
    "Maps the sequence's frames before --map-until seconds (default: all), then relocalizes\n"
    "every N-th frame (default 10) from --from seconds on (default 0) against that map, and\n"
    "prints: keyframes in the map, attempts, found, wrong (> 0.5 m), milliseconds per attempt\n"
    "(relocalization; feature extraction apart), and the found poses' error against ground\n"
    "truth relative to their keyframe.\n";

double NowMs() {
  return std::chrono::duration<double, std::milli>(
             std::chrono::steady_clock::now().time_since_epoch())
      .count();
}

double Percentile(std::vector<double> values, double p) {
  if (values.empty()) return std::nan("");
  std::sort(values.begin(), values.end());
  return values[static_cast<std::size_t>(p * (values.size() - 1) + 0.5)];
}

// [s] Ground truth is interpolated between two poses at most this far apart (EuRoC: 5 ms).
constexpr double kGroundTruthMaxGap = 0.02;

}  // namespace

int main(int argc, char** argv) {
  std::optional<tools::CommandLine> args;
  try {
    args.emplace(argc, argv,
                 std::set<std::string>{"map-until", "from", "every", "config", "fabmap-config"},
                 std::set<std::string>{"help"});
    if (args->Flag("help")) {
      std::fputs(kUsage, stdout);
      return 0;
    }
    if (args->positional().size() != 1) throw std::invalid_argument("expected one ASL_DIR");
  } catch (const std::invalid_argument& error) {
    std::fprintf(stderr, "benchmark_relocalization: %s\n%s", error.what(), kUsage);
    return 2;
  }
  try {
    tools::SlamConfiguration options = tools::SlamConfiguration::Load(
        args->ValueOr("config", STEREO_FABMAP_SLAM_CONFIG_DIR "/euroc.yaml"));
    const place_recognition::PlaceRecognitionOptions place_options = options.LoadPlaceRecognition(
        args->ValueOr("fabmap-config", STEREO_FABMAP_SLAM_CONFIG_DIR "/fabmap.yaml"));
    const datasets::EurocSequence sequence = datasets::EurocSequence::Open(args->positional()[0]);
    if (!sequence.has_ground_truth())
      throw std::invalid_argument("the sequence has no ground truth");
    const camera::StereoRectifier rectifier =
        camera::StereoRectifier::FromCalibration(sequence.calibration(), options.rectification);
    const evaluation::Trajectory truth = evaluation::TransformToSensorFrame(
        sequence.ground_truth(), rectifier.T_body_rectified_left());
    pipeline::StereoSlam slam(options.front_end, options.bundle_adjustment, rectifier, NowMs);
    options.EnableLoopClosing(place_options, rectifier, &slam);

    const double start = sequence.frames().front().timestamp_ns * 1e-9;
    const double map_until = args->NumberOr("map-until", std::numeric_limits<double>::max());
    const double from = args->NumberOr("from", 0.0);
    const int every = static_cast<int>(args->NumberOr("every", 10));
    for (std::size_t i = 0; i < sequence.size(); ++i) {
      if (sequence.frames()[i].timestamp_ns * 1e-9 - start >= map_until) break;
      const datasets::StereoImages images = sequence.LoadStereoPair(i);
      slam.ProcessFrame(images.timestamp_ns * 1e-9, images.left, images.right);
    }

    std::vector<double> ms, extraction_ms, translation_cm, rotation_deg;
    int attempts = 0, wrong = 0, without_truth = 0;  // found, but no ground truth to measure
    for (std::size_t i = 0; i < sequence.size(); i += static_cast<std::size_t>(every)) {
      const double time = sequence.frames()[i].timestamp_ns * 1e-9;
      if (time - start < from) continue;
      const datasets::StereoImages images = sequence.LoadStereoPair(i);
      const pipeline::RelocalizationOutput found = slam.Relocalize(images.left, images.right);
      ++attempts;
      ms.push_back(found.ms);
      extraction_ms.push_back(found.extraction_ms);
      if (!found.result.success()) continue;
      const std::optional<Eigen::Isometry3d> keyframe_truth = evaluation::InterpolatePose(
          truth, slam.KeyframeTime(found.result.keyframe_id), kGroundTruthMaxGap);
      const std::optional<Eigen::Isometry3d> frame_truth =
          evaluation::InterpolatePose(truth, time, kGroundTruthMaxGap);
      if (!keyframe_truth || !frame_truth) {
        ++without_truth;
        continue;
      }
      const Eigen::Isometry3d expected = keyframe_truth->inverse() * *frame_truth;
      const Eigen::Isometry3d error = expected.inverse() * found.result.T_keyframe_camera;
      translation_cm.push_back(100 * error.translation().norm());
      rotation_deg.push_back(Eigen::AngleAxisd(error.linear()).angle() * 180 / M_PI);
      wrong += error.translation().norm() > 0.5 ? 1 : 0;
    }
    const std::size_t keyframes = slam.mapping().pose_graph().size();
    std::printf("map keyframes                %zu\n", keyframes);
    std::printf("attempts                     %d (every %d-th frame from %.1f s)\n", attempts,
                every, from);
    const std::size_t found = translation_cm.size() + static_cast<std::size_t>(without_truth);
    std::printf("found                        %zu (%.1f %%; %d without ground truth to measure)\n",
                found, attempts > 0 ? 100.0 * found / attempts : 0.0, without_truth);
    std::printf("wrong (> 0.5 m)              %d\n", wrong);
    std::printf("relocalization ms            median %.2f  p90 %.2f  max %.2f\n",
                Percentile(ms, 0.5), Percentile(ms, 0.9), Percentile(ms, 1.0));
    std::printf("feature extraction ms        median %.2f\n", Percentile(extraction_ms, 0.5));
    std::printf("error vs ground truth        median %.2f cm %.3f deg, p90 %.2f cm %.3f deg\n",
                Percentile(translation_cm, 0.5), Percentile(rotation_deg, 0.5),
                Percentile(translation_cm, 0.9), Percentile(rotation_deg, 0.9));
  } catch (const std::exception& error) {
    std::fprintf(stderr, "benchmark_relocalization: %s\n", error.what());
    return 1;
  }
  return 0;
}
