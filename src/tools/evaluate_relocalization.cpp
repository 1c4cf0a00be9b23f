// The thesis' relocalization measure: maps part of an EuRoC-layout sequence (a real one or a
// rendered route) with the offline SLAM, then relocalizes every later frame against that map
// with mapping off (as the relocalize service does: no tracking, nothing changed) and measures
// recall against the frames that could have been relocalized: those that see enough of some
// keyframe's points, by ground truth.
#include <cmath>
#include <cstdio>
#include <exception>
#include <filesystem>
#include <fstream>
#include <limits>
#include <map>
#include <optional>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

#include "command_line.h"
#include "slam_configuration.h"
#include "stereo_fabmap_slam/datasets/euroc_sequence.h"
#include "stereo_fabmap_slam/evaluation/pose_interpolation.h"
#include "stereo_fabmap_slam/evaluation/relocalization_recall.h"
#include "stereo_fabmap_slam/pipeline/stereo_slam.h"

namespace {

using namespace stereo_fabmap_slam;  // NOLINT: a tool's main file

constexpr char kUsage[] =
    "usage: evaluate_relocalization ASL_DIR [--map-until S | --map-segments A-B,C-D]\n"
    "                               [--every N] [--tau T] [--dmax M] [--json] [--output DIR]\n"
    "                               [--config FILE] [--fabmap-config FILE] [--quiet]\n"
    "Maps the frames of the mapping segments (seconds from the first frame; --map-until S is\n"
    "0-S; default: the first half of the frames with ground truth), then relocalizes every N-th "
    "other frame (default 1) that has\n"
    "ground truth against that map, mapping off. A test frame is relevant at tau when at least\n"
    "the fraction tau of some keyframe's 3-D points, carried by ground truth into it, land in\n"
    "its image; recall(tau, dmax) is the share of relevant frames relocalized with a\n"
    "keyframe-to-frame translation error of at most dmax metres (defaults 0.9, 0.5).\n"
    "  --json          print one JSON object (test_frames, relevant_frames, estimated_frames,\n"
    "                  recall, error_below_10cm_fraction, error_median_m, wrong_estimates, ...)\n"
    "  --output DIR    write frames.csv (every frame: ground truth, mapping, relevance,\n"
    "                  estimate, the relocalizer's outcome), recall.csv (recall against tau\n"
    "                  for dmax 0.1, 0.25, 0.5, 1 m), summary.json (as --json, with the count\n"
    "                  of each outcome)\n"
    "  --quiet         no progress on stderr\n";

// [s] A frame's ground truth is interpolated between two poses at most this far apart (EuRoC's
// come every 5 ms; a longer gap is a hole in the ground truth, and the frame is not judged).
constexpr double kGroundTruthMaxGap = 0.02;

struct Segment {
  double from = 0, to = 0;  // [s] from the first frame
};

std::vector<Segment> ParseSegments(const std::string& text) {
  std::vector<Segment> segments;
  std::stringstream list(text);
  std::string item;
  while (std::getline(list, item, ',')) {
    const std::size_t dash = item.find('-', 1);
    try {
      if (dash == std::string::npos) throw std::invalid_argument("");
      std::size_t used_from = 0, used_to = 0;
      const std::string from = item.substr(0, dash), to = item.substr(dash + 1);
      Segment segment{std::stod(from, &used_from), std::stod(to, &used_to)};
      if (used_from != from.size() || used_to != to.size() || !(segment.to > segment.from))
        throw std::invalid_argument("");
      segments.push_back(segment);
    } catch (const std::exception&) {
      throw std::invalid_argument("--map-segments: '" + item +
                                  "' is not a segment A-B of seconds with A < B");
    }
  }
  if (segments.empty()) throw std::invalid_argument("--map-segments: no segment given");
  return segments;
}

bool InSegments(const std::vector<Segment>& segments, double seconds) {
  for (const Segment& segment : segments) {
    if (seconds >= segment.from && seconds < segment.to) return true;
  }
  return false;
}

// A keyframe as the measure sees it: its stereo points and its ground-truth camera pose.
struct KeyframeTruth {
  std::int64_t id = 0;
  std::vector<Eigen::Vector3d> points;
  Eigen::Isometry3d T_world_camera = Eigen::Isometry3d::Identity();
};

std::vector<KeyframeTruth> MapKeyframes(const pipeline::StereoSlam& slam,
                                        const evaluation::Trajectory& truth) {
  std::vector<KeyframeTruth> keyframes;
  for (const auto& [id, stored] : slam.place()->detector().database().keyframes()) {
    const std::optional<Eigen::Isometry3d> pose =
        evaluation::InterpolatePose(truth, stored.keyframe.timestamp, kGroundTruthMaxGap);
    if (!pose) continue;  // without ground truth it cannot be judged relevant
    KeyframeTruth keyframe{id, {}, *pose};
    const features::StereoFeatures& features = stored.keyframe.features;
    for (std::size_t i = 0; i < features.size(); ++i) {
      if (features.HasDepth(i)) keyframe.points.push_back(features.points[i]);
    }
    keyframes.push_back(std::move(keyframe));
  }
  return keyframes;
}

// One row of frames.csv.
struct FrameRow {
  double seconds = 0;
  bool mapping = false;
  std::optional<Eigen::Isometry3d> truth;
  std::optional<evaluation::RelocalizationTrial> trial;
  std::optional<Eigen::Vector3d> keyframe_position;  // ground truth of the keyframe found
  std::string outcome;  // the relocalizer's status: why a test frame got no pose
};

std::string Number(double value) {
  if (!std::isfinite(value)) return "null";
  char buffer[32];
  std::snprintf(buffer, sizeof(buffer), "%.6g", value);
  return buffer;
}

// {"success": 63, "too few matches": 30, ...}: how the test frames' attempts ended.
std::string OutcomesJson(const std::map<std::string, int>& outcomes) {
  std::string json = "{";
  for (const auto& [outcome, count] : outcomes) {
    json += (json.size() > 1 ? ", \"" : "\"") + outcome + "\": " + std::to_string(count);
  }
  return json + "}";
}

std::string SummaryJson(const std::string& sequence, const evaluation::RelocalizationSummary& s,
                        double tau, double dmax, std::size_t keyframes, std::size_t map_frames,
                        const std::map<std::string, int>& outcomes, int unmeasured) {
  return "{\"sequence\": \"" + sequence + "\", \"map_frames\": " + std::to_string(map_frames) +
         ", \"map_keyframes\": " + std::to_string(keyframes) +
         ", \"test_frames\": " + std::to_string(s.test_frames) +
         ", \"relevant_frames\": " + std::to_string(s.relevant_frames) +
         ", \"estimated_frames\": " + std::to_string(s.estimated_frames) +
         ", \"tau\": " + Number(tau) + ", \"dmax_m\": " + Number(dmax) +
         ", \"recall\": " + Number(s.recall) +
         ", \"error_below_10cm_fraction\": " + Number(s.error_below_10cm_fraction) +
         ", \"error_median_m\": " + Number(s.error_median_m) +
         ", \"wrong_estimates\": " + std::to_string(s.wrong_estimates) +
         ", \"unmeasured_estimates\": " + std::to_string(unmeasured) +
         ", \"outcomes\": " + OutcomesJson(outcomes) + "}\n";
}

void WriteText(const std::string& path, const std::string& text) {
  std::ofstream file(path);
  file << text;
  if (!file) throw std::runtime_error("cannot write " + path);
}

void WriteOutputs(const std::string& directory, const std::vector<FrameRow>& rows,
                  const std::vector<evaluation::RelocalizationTrial>& trials,
                  const std::string& summary_json) {
  std::string frames =
      "time,mapping,x,y,z,relevance,estimated,keyframe,keyframe_x,keyframe_y,keyframe_z,"
      "error_m,estimated_distance_m,outcome\n";
  for (const FrameRow& row : rows) {
    frames += Number(row.seconds) + "," + (row.mapping ? "1" : "0");
    for (int axis = 0; axis < 3; ++axis)
      frames += "," + (row.truth ? Number(row.truth->translation()[axis]) : std::string());
    if (row.trial) {
      frames += "," + Number(row.trial->relevance) + "," + (row.trial->estimated ? "1" : "0");
    } else {
      frames += ",,";
    }
    if (row.trial && row.trial->estimated && row.keyframe_position) {
      frames += "," + std::to_string(row.trial->keyframe_id);
      for (int axis = 0; axis < 3; ++axis) frames += "," + Number((*row.keyframe_position)[axis]);
      frames += "," + Number(row.trial->error_m) + "," + Number(row.trial->estimated_distance_m);
    } else {
      frames += ",,,,,,";
    }
    frames += "," + row.outcome + "\n";
  }
  WriteText(directory + "/frames.csv", frames);

  std::string recall = "tau,dmax_m,recall,relevant_frames\n";
  for (const double dmax : {0.1, 0.25, 0.5, 1.0}) {
    for (int step = 0; step <= 20; ++step) {
      const double tau = 0.05 * step;
      recall +=
          Number(tau) + "," + Number(dmax) + "," +
          Number(evaluation::RelocalizationRecall(trials, tau, dmax)) + "," +
          std::to_string(evaluation::SummarizeRelocalization(trials, tau, dmax).relevant_frames) +
          "\n";
    }
  }
  WriteText(directory + "/recall.csv", recall);
  WriteText(directory + "/summary.json", summary_json);
}

}  // namespace

int main(int argc, char** argv) {
  std::optional<tools::CommandLine> args;
  try {
    args.emplace(argc, argv,
                 std::set<std::string>{"map-until", "map-segments", "every", "tau", "dmax",
                                       "output", "config", "fabmap-config"},
                 std::set<std::string>{"help", "json", "quiet"});
    if (args->Flag("help")) {
      std::fputs(kUsage, stdout);
      return 0;
    }
    if (args->positional().size() != 1) throw std::invalid_argument("expected one ASL_DIR");
    if (args->Value("map-until") && args->Value("map-segments"))
      throw std::invalid_argument("give --map-until or --map-segments, not both");
    if (args->NumberOr("every", 1) < 1) throw std::invalid_argument("--every must be at least 1");
  } catch (const std::invalid_argument& error) {
    std::fprintf(stderr, "evaluate_relocalization: %s\n%s", error.what(), kUsage);
    return 2;
  }
  try {
    tools::SlamConfiguration options = tools::SlamConfiguration::Load(
        args->ValueOr("config", STEREO_FABMAP_SLAM_CONFIG_DIR "/euroc.yaml"));
    const place_recognition::PlaceRecognitionOptions place_options = options.LoadPlaceRecognition(
        args->ValueOr("fabmap-config", STEREO_FABMAP_SLAM_CONFIG_DIR "/fabmap.yaml"));
    const datasets::EurocSequence sequence = datasets::EurocSequence::Open(args->positional()[0]);
    if (sequence.size() == 0) throw std::invalid_argument("the sequence has no stereo frames");
    if (!sequence.has_ground_truth())
      throw std::invalid_argument("the sequence has no ground truth: relevance needs it");
    const camera::StereoRectifier rectifier =
        camera::StereoRectifier::FromCalibration(sequence.calibration(), options.rectification);
    const evaluation::Trajectory truth = evaluation::TransformToSensorFrame(
        sequence.ground_truth(), rectifier.T_body_rectified_left());

    const double start = sequence.frames().front().timestamp_ns * 1e-9;
    const double length = sequence.frames().back().timestamp_ns * 1e-9 - start;
    // By default the first half of the frames with ground truth is mapped: a keyframe mapped
    // before the ground truth begins (EuRoC's first seconds) could be found but not measured.
    double truth_start = length;
    for (const datasets::StereoFrameEntry& frame : sequence.frames()) {
      if (evaluation::InterpolatePose(truth, frame.timestamp_ns * 1e-9, kGroundTruthMaxGap)) {
        truth_start = frame.timestamp_ns * 1e-9 - start;
        break;
      }
    }
    std::vector<Segment> segments{{truth_start, truth_start + 0.5 * (length - truth_start)}};
    if (args->Value("map-until")) segments = {{0.0, args->NumberOr("map-until", 0)}};
    if (args->Value("map-segments")) segments = ParseSegments(*args->Value("map-segments"));
    const double tau = args->NumberOr("tau", 0.9), dmax = args->NumberOr("dmax", 0.5);
    const int every = static_cast<int>(args->NumberOr("every", 1));
    const bool quiet = args->Flag("quiet");

    pipeline::StereoSlam slam(options.front_end, options.bundle_adjustment, rectifier,
                              [] { return 0.0; });  // times are not measured here
    options.EnableLoopClosing(place_options, rectifier, &slam);
    std::vector<FrameRow> rows(sequence.size());
    std::size_t map_frames = 0;
    for (std::size_t i = 0; i < sequence.size(); ++i) {
      rows[i].seconds = sequence.frames()[i].timestamp_ns * 1e-9 - start;
      rows[i].mapping = InSegments(segments, rows[i].seconds);
      rows[i].truth = evaluation::InterpolatePose(truth, sequence.frames()[i].timestamp_ns * 1e-9,
                                                  kGroundTruthMaxGap);
      if (!rows[i].mapping) continue;
      const datasets::StereoImages images = sequence.LoadStereoPair(i);
      slam.ProcessFrame(images.timestamp_ns * 1e-9, images.left, images.right);
      ++map_frames;
      if (!quiet && map_frames % 100 == 0)
        std::fprintf(stderr, "mapping: %zu frames, %zu keyframes\n", map_frames,
                     slam.keyframe_count());
    }
    if (map_frames == 0) throw std::invalid_argument("no frame lies in the mapping segments");
    const std::vector<KeyframeTruth> keyframes = MapKeyframes(slam, truth);

    std::vector<evaluation::RelocalizationTrial> trials;
    std::map<std::string, int> outcomes;
    int candidates = 0, unmeasured = 0;
    for (std::size_t i = 0; i < sequence.size(); ++i) {
      FrameRow& row = rows[i];
      if (row.mapping || !row.truth) continue;
      if (candidates++ % every != 0) continue;
      evaluation::RelocalizationTrial trial;
      trial.timestamp = sequence.frames()[i].timestamp_ns * 1e-9;
      for (const KeyframeTruth& keyframe : keyframes) {
        trial.relevance = std::max(
            trial.relevance, evaluation::VisibleFraction(
                                 keyframe.points, row.truth->inverse() * keyframe.T_world_camera,
                                 rectifier.camera()));
      }
      const datasets::StereoImages images = sequence.LoadStereoPair(i);
      const pipeline::RelocalizationOutput found = slam.Relocalize(images.left, images.right);
      if (found.result.success()) {
        const std::optional<Eigen::Isometry3d> keyframe_truth = evaluation::InterpolatePose(
            truth, slam.KeyframeTime(found.result.keyframe_id), kGroundTruthMaxGap);
        if (keyframe_truth) {
          const Eigen::Isometry3d expected = keyframe_truth->inverse() * *row.truth;
          trial.estimated = true;
          trial.keyframe_id = found.result.keyframe_id;
          trial.error_m =
              (found.result.T_keyframe_camera.translation() - expected.translation()).norm();
          trial.estimated_distance_m = found.result.T_keyframe_camera.translation().norm();
          row.keyframe_position = keyframe_truth->translation();
        } else {
          ++unmeasured;  // found against a keyframe mapped before the ground truth begins
        }
      }
      row.outcome = relocalization::RelocalizationStatusName(found.result.status);
      ++outcomes[row.outcome];
      row.trial = trial;
      trials.push_back(trial);
      if (!quiet && trials.size() % 100 == 0)
        std::fprintf(stderr, "relocalizing: %zu test frames\n", trials.size());
    }
    if (trials.empty())
      throw std::invalid_argument("no test frame with ground truth outside the mapping segments");

    const evaluation::RelocalizationSummary summary =
        evaluation::SummarizeRelocalization(trials, tau, dmax);
    const std::string json = SummaryJson(args->positional()[0], summary, tau, dmax,
                                         keyframes.size(), map_frames, outcomes, unmeasured);
    if (args->Value("output")) {
      std::filesystem::create_directories(*args->Value("output"));
      WriteOutputs(*args->Value("output"), rows, trials, json);
    }
    if (args->Flag("json")) {
      std::fputs(json.c_str(), stdout);
      return 0;
    }
    std::printf("map                          %zu frames, %zu keyframes\n", map_frames,
                keyframes.size());
    std::printf("test frames                  %d (one in %d of the frames outside the map)\n",
                summary.test_frames, every);
    std::printf("relevant (tau %.2f)           %d\n", tau, summary.relevant_frames);
    std::printf("estimated                    %d (%.1f %%)\n", summary.estimated_frames,
                100.0 * summary.estimated_frames / summary.test_frames);
    std::printf("recall (tau %.2f, dmax %.2f m) %.3f\n", tau, dmax, summary.recall);
    std::printf("estimates within 10 cm       %.1f %%\n", 100 * summary.error_below_10cm_fraction);
    std::printf("median error                 %.3f m\n", summary.error_median_m);
    std::printf("wrong (error > dmax)         %d\n", summary.wrong_estimates);
    if (unmeasured > 0)
      std::printf(
          "unmeasured                   %d (found against a keyframe without ground truth)\n",
          unmeasured);
    for (const auto& [outcome, count] : outcomes)
      std::printf("  attempts ending '%s'%*s%d\n", outcome.c_str(),
                  std::max(1, 24 - static_cast<int>(outcome.size())), "", count);
  } catch (const std::exception& error) {
    std::fprintf(stderr, "evaluate_relocalization: %s\n", error.what());
    return 1;
  }
  return 0;
}
