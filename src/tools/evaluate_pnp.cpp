// The thesis' PnP kernel study (issue 13, part 2): for reference frames of EuRoC-layout sequences
// with ground truth, the stereo points of the reference; for test frames at growing distance,
// their key points matched to those points by descriptor; every PnP kernel inside the same
// RANSAC, with and without the pose refinement. Writes pnp.csv (per distance bin) and
// pnp_summary.csv (per sequence), and prints the tables.
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <exception>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <map>
#include <optional>
#include <set>
#include <string>
#include <vector>

#include "command_line.h"
#include "slam_configuration.h"
#include "stereo_fabmap_slam/camera/stereo_rectifier.h"
#include "stereo_fabmap_slam/datasets/euroc_sequence.h"
#include "stereo_fabmap_slam/evaluation/pnp_study.h"
#include "stereo_fabmap_slam/evaluation/pose_interpolation.h"
#include "stereo_fabmap_slam/evaluation/trajectory.h"
#include "stereo_fabmap_slam/features/stereo_feature_extractor.h"

namespace {

using namespace stereo_fabmap_slam;  // NOLINT: a tool's main file

constexpr char kUsage[] =
    "usage: evaluate_pnp ASL_DIR... [--output DIR] [--reference-every N] [--per-bin K]\n"
    "                    [--max-distance M] [--bin-width M] [--config FILE]\n"
    "PnP kernel study: every N-th frame with ground truth (default 10) is a reference, whose\n"
    "stereo points the later frames within --max-distance metres (default 2) match by\n"
    "descriptor; of those, K per reference and distance bin (default 3, spread in time) are\n"
    "test frames. Each kernel (ITERATIVE, EPNP, AP3P, P3P, SQPNP, UMEYAMA) runs in the same\n"
    "RANSAC (the relocalization section's threshold, iterations, ratio and inlier minimum),\n"
    "with and without the pose refinement. Features from the config (default euroc.yaml).\n"
    "Writes DIR/pnp.csv (per kernel, refinement and distance bin of --bin-width metres,\n"
    "default 0.1) and DIR/pnp_summary.csv (per sequence), default DIR output/pnp, and prints\n"
    "a table per sequence.\n";

struct StudySettings {
  int reference_every = 10;
  int per_bin = 3;
  double max_distance = 2.0;
  double bin_width = 0.1;
};

double NowMs() {
  return std::chrono::duration<double, std::milli>(
             std::chrono::steady_clock::now().time_since_epoch())
      .count();
}

// "…/MH01/" and "…/MH01/mav0" are both named MH01.
std::string SequenceName(const std::string& directory) {
  std::filesystem::path path(directory);
  if (path.filename().empty()) path = path.parent_path();
  if (path.filename() == "mav0") path = path.parent_path();
  return path.filename().string();
}

struct Pair {
  std::size_t reference, test;
};

// References every `reference_every`-th frame with ground truth; test frames after it, at most
// `per_bin` per distance bin, spread evenly over the frames that fall into the bin so that a
// bin is not represented by a few consecutive, nearly identical views.
std::vector<Pair> ChoosePairs(const std::vector<std::optional<Eigen::Isometry3d>>& poses,
                              const StudySettings& settings) {
  std::vector<Pair> pairs;
  int with_truth = 0;
  for (std::size_t i = 0; i < poses.size(); ++i) {
    if (!poses[i]) continue;
    if (with_truth++ % settings.reference_every != 0) continue;
    std::map<long, std::vector<std::size_t>> bins;
    for (std::size_t j = i + 1; j < poses.size(); ++j) {
      if (!poses[j]) continue;
      const double distance = (poses[j]->translation() - poses[i]->translation()).norm();
      if (distance > settings.max_distance) continue;
      bins[static_cast<long>(distance / settings.bin_width)].push_back(j);
    }
    for (const auto& [bin, frames] : bins) {
      const std::size_t take = std::min(frames.size(), static_cast<std::size_t>(settings.per_bin));
      for (std::size_t k = 0; k < take; ++k) {
        pairs.push_back({i, frames[(2 * k + 1) * frames.size() / (2 * take)]});
      }
    }
  }
  return pairs;
}

std::vector<evaluation::PnpTrial> StudySequence(const std::string& directory,
                                                const tools::SlamConfiguration& options,
                                                const evaluation::PnpStudyOptions& study,
                                                const StudySettings& settings) {
  const std::string name = SequenceName(directory);
  const datasets::EurocSequence sequence = datasets::EurocSequence::Open(directory);
  if (sequence.size() == 0) throw std::invalid_argument(directory + " holds no stereo frames");
  if (!sequence.has_ground_truth()) throw std::invalid_argument(directory + " has no ground truth");
  const camera::StereoRectifier rectifier =
      camera::StereoRectifier::FromCalibration(sequence.calibration(), options.rectification);
  // Ground truth is the body's pose; the study needs the rectified left camera's (T_WB T_BS).
  const evaluation::Trajectory truth = evaluation::TransformToSensorFrame(
      sequence.ground_truth(), rectifier.T_body_rectified_left());
  // Each frame's ground truth interpolated between poses at most 20 ms apart (EuRoC: 5 ms).
  std::vector<std::optional<Eigen::Isometry3d>> poses(sequence.size());
  for (std::size_t i = 0; i < sequence.size(); ++i) {
    poses[i] = evaluation::InterpolatePose(truth, sequence.frames()[i].timestamp_ns * 1e-9, 0.02);
  }
  const std::vector<Pair> pairs = ChoosePairs(poses, settings);
  if (pairs.empty()) {
    throw std::invalid_argument(name + ": no two frames with ground truth within --max-distance");
  }

  // Features of every frame a pair needs, extracted in time order as the odometry would (the
  // detector adapts its threshold along the stream).
  std::set<std::size_t> needed;
  for (const Pair& pair : pairs) needed.insert({pair.reference, pair.test});
  features::StereoFeatureExtractor extractor(options.front_end.features, options.front_end.stereo,
                                             rectifier.camera());
  std::map<std::size_t, features::StereoFeatures> features;
  for (const std::size_t i : needed) {
    const datasets::StereoImages images = sequence.LoadStereoPair(i);
    cv::Mat left, right;
    rectifier.Rectify(images.left, images.right, &left, &right);
    features.emplace(i, extractor.Extract(left, right));
    if (features.size() % 50 == 0 || features.size() == needed.size()) {
      std::fprintf(stderr, "%s: features of %zu / %zu frames\n", name.c_str(), features.size(),
                   needed.size());
    }
  }

  const std::vector<geometry::PnpKernel> kernels = evaluation::AllPnpKernels();
  std::vector<evaluation::PnpTrial> trials;
  for (std::size_t p = 0; p < pairs.size(); ++p) {
    const Pair& pair = pairs[p];
    const geometry::PointMatches matches = evaluation::MatchToReference(
        features.at(pair.reference), features.at(pair.test), extractor.descriptor_norm(),
        extractor.max_match_distance(), study.match_ratio);
    const Eigen::Isometry3d true_T_test_reference =
        poses[pair.test]->inverse() * *poses[pair.reference];
    const std::vector<evaluation::PnpTrial> pair_trials = evaluation::RunPnpKernels(
        matches, rectifier.camera(), true_T_test_reference, kernels, study, NowMs);
    trials.insert(trials.end(), pair_trials.begin(), pair_trials.end());
    if ((p + 1) % 100 == 0 || p + 1 == pairs.size()) {
      std::fprintf(stderr, "%s: %zu / %zu reference-test pairs\n", name.c_str(), p + 1,
                   pairs.size());
    }
  }
  return trials;
}

}  // namespace

int main(int argc, char** argv) {
  std::optional<tools::CommandLine> args;
  StudySettings settings;
  try {
    args.emplace(argc, argv,
                 std::set<std::string>{"output", "reference-every", "per-bin", "max-distance",
                                       "bin-width", "config"},
                 std::set<std::string>{"help"});
    if (args->Flag("help")) {
      std::fputs(kUsage, stdout);
      return 0;
    }
    if (args->positional().empty()) throw std::invalid_argument("expected at least one ASL_DIR");
    const double every = args->NumberOr("reference-every", settings.reference_every);
    const double per_bin = args->NumberOr("per-bin", settings.per_bin);
    settings.max_distance = args->NumberOr("max-distance", settings.max_distance);
    settings.bin_width = args->NumberOr("bin-width", settings.bin_width);
    if (every < 1 || every != static_cast<int>(every)) {
      throw std::invalid_argument("--reference-every must be a whole number >= 1");
    }
    if (per_bin < 1 || per_bin != static_cast<int>(per_bin)) {
      throw std::invalid_argument("--per-bin must be a whole number >= 1");
    }
    if (!(settings.max_distance > 0) || !(settings.bin_width > 0)) {
      throw std::invalid_argument("--max-distance and --bin-width must be > 0");
    }
    settings.reference_every = static_cast<int>(every);
    settings.per_bin = static_cast<int>(per_bin);
  } catch (const std::invalid_argument& error) {
    std::fprintf(stderr, "evaluate_pnp: %s\n%s", error.what(), kUsage);
    return 2;
  }
  try {
    const tools::SlamConfiguration options = tools::SlamConfiguration::Load(
        args->ValueOr("config", STEREO_FABMAP_SLAM_CONFIG_DIR "/euroc.yaml"));
    // The relocalizer's RANSAC and acceptance: the study asks which kernel it should use.
    evaluation::PnpStudyOptions study;
    study.match_ratio = options.relocalization.match_ratio;
    study.ransac.reprojection_threshold = options.relocalization.ransac_threshold;
    study.ransac.max_iterations = options.relocalization.ransac_iterations;
    study.min_inliers = options.relocalization.min_ransac_inliers;
    study.refinement = options.front_end.tracker.refinement;
    study.Validate();

    const std::string output = args->ValueOr("output", "output/pnp");
    std::filesystem::create_directories(output);
    std::ofstream by_distance(output + "/pnp.csv"), summary(output + "/pnp_summary.csv");
    if (!by_distance || !summary) throw std::runtime_error("cannot write into " + output);
    evaluation::WritePnpCsvHeader(by_distance, true);
    evaluation::WritePnpCsvHeader(summary, false);
    for (const std::string& directory : args->positional()) {
      const double start = NowMs();
      const std::string name = SequenceName(directory);
      const std::vector<evaluation::PnpTrial> trials =
          StudySequence(directory, options, study, settings);
      const std::vector<evaluation::PnpStatistics> rows =
          evaluation::AggregatePnpTrials(trials, settings.bin_width);
      const std::vector<evaluation::PnpStatistics> table = evaluation::SummarizePnpTrials(trials);
      evaluation::WritePnpCsvRows(by_distance, name, rows, true);
      evaluation::WritePnpCsvRows(summary, name, table, false);
      evaluation::PrintPnpTable(
          std::cout,
          name + " (" + std::to_string(trials.size() / (2 * evaluation::AllPnpKernels().size())) +
              " reference-test pairs, errors over successes)",
          table, false);
      std::cout << std::endl;
      std::fprintf(stderr, "%s: done in %.1f s\n", name.c_str(), (NowMs() - start) / 1000.0);
    }
    by_distance.close();
    summary.close();
    if (!by_distance || !summary) throw std::runtime_error("cannot write into " + output);
    std::fprintf(stderr, "wrote %s/pnp.csv and %s/pnp_summary.csv\n", output.c_str(),
                 output.c_str());
  } catch (const std::exception& error) {
    std::fprintf(stderr, "evaluate_pnp: %s\n", error.what());
    return 1;
  }
  return 0;
}
