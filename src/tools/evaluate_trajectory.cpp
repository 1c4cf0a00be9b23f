// Compares an estimated trajectory with ground truth: ATE (evo_ape -a convention) and RPE.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <exception>
#include <optional>
#include <string>

#include <opencv2/imgcodecs.hpp>

#include "command_line.h"
#include "stereo_fabmap_slam/camera/camera_calibration.h"
#include "stereo_fabmap_slam/camera/stereo_rectifier.h"
#include "stereo_fabmap_slam/evaluation/trajectory_metrics.h"
#include "stereo_fabmap_slam/evaluation/trajectory_plot.h"
#include "stereo_fabmap_slam/io/csv_reader.h"
#include "stereo_fabmap_slam/io/trajectory_file.h"

namespace {

using namespace stereo_fabmap_slam;  // NOLINT: a tool's main file

constexpr char kUsage[] =
    "usage: evaluate_trajectory --gt FILE --est FILE [--align se3|sim3|none] [--max-dt S]\n"
    "                           [--gt-to-camera sensor.yaml | --gt-to-base stereo.yaml |\n"
    "                            --gt-to-rectified stereo.yaml]\n"
    "                           [--rpe-delta D] [--rpe-unit frames|m] [--json] [--plot out.png]\n"
    "                           [--keyframes FILE] [--loops FILE] [--relocalizations FILE]\n"
    "Trajectory files: TUM (t x y z qx qy qz qw), EuRoC CSV (.csv, stamps in ns) or KITTI (3x4).\n"
    "ATE: positions of the estimate aligned to the ground truth (Umeyama, --align, default se3),\n"
    "then RMSE/mean/median/max of the position differences, as evo_ape -a.\n"
    "RPE: for every matched pose i and the pose j --rpe-delta later (default 1 frame), the\n"
    "translation norm and angle of (GT_i^-1 GT_j)^-1 (EST_i^-1 EST_j).\n"
    "--gt-to-camera: the ground truth of the body moved to the camera of a sensor.yaml (T_BS),\n"
    "as the offline runner's camera trajectories; --gt-to-base: moved to the base of a stereo\n"
    "calibration (its T_body_base, e.g. config/euroc_stereo.yaml), as the nodelets' odometry;\n"
    "--gt-to-rectified: moved to the rectified left camera of a stereo calibration, as the\n"
    "trajectory files of run_dataset and of the graph (output:=DIR) estimate it.\n"
    "--plot: a top view (x-y) and a side view (x-z) of ground truth and aligned estimate, with\n"
    "the keyframes, loop edges and relocalizations given.\n"
    "--loops FILE, --relocalizations FILE: lines 'query_time match_time' (the two keyframes of\n"
    "each loop edge or relocalization), drawn in the plot.\n"
    "--poses FILE: more poses in the estimate's frame (e.g. relocalizations, TUM), measured\n"
    "with the estimate's alignment: one line each, 'pose T: E m, A deg' (not with --json).\n";

// Reads a trajectory and tells on stderr what in it another tool may have meant differently.
evaluation::Trajectory ReadWithWarnings(const std::string& path) {
  io::TrajectoryFileNotes notes;
  evaluation::Trajectory trajectory = io::ReadTrajectory(path, &notes);
  if (notes.header_skipped) {
    std::fprintf(stderr, "evaluate_trajectory: %s: first row taken as a header\n", path.c_str());
  }
  if (notes.repeated_stamps > 0 || notes.unordered_stamps > 0) {
    std::fprintf(stderr,
                 "evaluate_trajectory: warning: %s: %zu repeated and %zu decreasing timestamps; "
                 "every pose is kept, and each pose of the shorter file takes the pose of the "
                 "other nearest in time, the first on a tie (as evo associates)\n",
                 path.c_str(), notes.repeated_stamps, notes.unordered_stamps);
  }
  return trajectory;
}

void PrintStatsRow(const char* name, const evaluation::ErrorStatistics& s, double unit_scale) {
  std::printf("%-16s %10.4f %10.4f %10.4f %10.4f %8zu\n", name, s.rmse * unit_scale,
              s.mean * unit_scale, s.median * unit_scale, s.max * unit_scale, s.count);
}

void PrintTable(const evaluation::EvaluationResult& r, const evaluation::EvaluationOptions& o,
                const std::string& gt, const std::string& est) {
  std::printf("ground truth  %s\n", gt.c_str());
  std::printf("estimate      %s\n", est.c_str());
  std::printf("matched       %zu of %zu estimated poses (max dt %.4f s)\n", r.matched,
              r.estimated_poses, o.max_dt);
  std::printf("alignment     %s, scale %.6f\n\n", evaluation::AlignmentModeName(o.alignment),
              r.alignment.scale);
  std::printf("%-16s %10s %10s %10s %10s %8s\n", "", "rmse", "mean", "median", "max", "count");
  PrintStatsRow("ATE [cm]", r.ate, 100.0);
  PrintStatsRow("RPE trans [cm]", r.rpe.translation, 100.0);
  PrintStatsRow("RPE rot [deg]", r.rpe.rotation_deg, 1.0);
  std::printf("\nRPE step: %g %s\n", o.rpe_delta.value,
              o.rpe_delta.unit == evaluation::RpeDelta::Unit::kFrames ? "frame(s)" : "m");
}

void PrintJson(const evaluation::EvaluationResult& r, const evaluation::EvaluationOptions& o) {
  std::printf(
      "{\"ate_rmse\": %.9g, \"ate_mean\": %.9g, \"ate_median\": %.9g, \"ate_max\": %.9g, "
      "\"matched\": %zu, \"estimated_poses\": %zu, \"alignment\": \"%s\", \"scale\": %.9g, "
      "\"rpe_trans_rmse\": %.9g, \"rpe_trans_mean\": %.9g, \"rpe_rot_rmse_deg\": %.9g, "
      "\"rpe_rot_mean_deg\": %.9g, \"rpe_pairs\": %zu, \"rpe_delta\": %.9g, "
      "\"rpe_unit\": \"%s\"}\n",
      r.ate.rmse, r.ate.mean, r.ate.median, r.ate.max, r.matched, r.estimated_poses,
      evaluation::AlignmentModeName(o.alignment), r.alignment.scale, r.rpe.translation.rmse,
      r.rpe.translation.mean, r.rpe.rotation_deg.rmse, r.rpe.rotation_deg.mean,
      r.rpe.translation.count, o.rpe_delta.value,
      o.rpe_delta.unit == evaluation::RpeDelta::Unit::kFrames ? "frames" : "m");
}

// The aligned position of the pose of `trajectory` nearest in time to `time`.
Eigen::Vector3d NearestPosition(const evaluation::Trajectory& trajectory,
                                const evaluation::EvaluationResult& r, double time) {
  const evaluation::StampedPose* nearest = &trajectory.front();
  for (const auto& p : trajectory) {
    if (std::abs(p.timestamp - time) < std::abs(nearest->timestamp - time)) nearest = &p;
  }
  return r.alignment * nearest->pose.translation();
}

using TimePairs = std::vector<std::pair<double, double>>;

// Lines "time time" of a file (loop edges, relocalizations).
TimePairs ReadTimePairs(const std::string& path) {
  TimePairs pairs;
  for (const io::TextRow& row : io::ReadDelimitedText(path, io::Separator::kWhitespace)) {
    if (row.fields.size() < 2) throw io::FileError(path, row.line_number, "expected two times");
    pairs.emplace_back(io::ParseDouble(row.fields[0], path, row.line_number),
                       io::ParseDouble(row.fields[1], path, row.line_number));
  }
  return pairs;
}

// `keyframes` (may be empty) are drawn with the estimate's alignment; `loops` and
// `relocalizations` (pairs of keyframe times, may be empty) as segments between the keyframes
// (or estimated poses) nearest those times. Top view on the left, side view on the right.
void WritePlot(const evaluation::EvaluationResult& r, const evaluation::Trajectory& keyframes,
               const evaluation::Trajectory& estimate_raw, const TimePairs& loops,
               const TimePairs& relocalizations, const std::string& path) {
  std::vector<Eigen::Vector3d> reference, estimate, keyframe_positions;
  for (const auto& p : r.matched_reference) reference.push_back(p.pose.translation());
  for (const auto& p : r.aligned_estimate) estimate.push_back(p.pose.translation());
  for (const auto& p : keyframes) keyframe_positions.push_back(r.alignment * p.pose.translation());
  evaluation::TrajectoryPlot plot;
  plot.AddPath(reference, cv::Scalar(80, 80, 80), "ground truth", 3);
  plot.AddPath(estimate, cv::Scalar(200, 90, 0), "estimate (aligned)", 2);
  if (!keyframe_positions.empty())
    plot.AddPoints(keyframe_positions, cv::Scalar(60, 150, 60), "keyframes", 3);
  const evaluation::Trajectory& ends = keyframes.empty() ? estimate_raw : keyframes;
  const auto segments_of = [&](const TimePairs& pairs) {
    std::vector<std::pair<Eigen::Vector3d, Eigen::Vector3d>> segments;
    for (const auto& [query, match] : pairs) {
      segments.emplace_back(NearestPosition(ends, r, query), NearestPosition(ends, r, match));
    }
    return segments;
  };
  if (!loops.empty())
    plot.AddSegments(segments_of(loops), cv::Scalar(40, 40, 230), "loop edges", 2);
  if (!relocalizations.empty()) {
    const auto segments = segments_of(relocalizations);
    plot.AddSegments(segments, cv::Scalar(200, 40, 200), "relocalizations", 2);
    std::vector<Eigen::Vector3d> found;
    for (const auto& segment : segments) found.push_back(segment.first);
    plot.AddPoints(found, cv::Scalar(200, 40, 200), "", 6);
  }
  char title[128];
  std::snprintf(title, sizeof(title), "top view (x-y): ATE RMSE %.2f cm over %zu poses",
                r.ate.rmse * 100.0, r.matched);
  cv::Mat image;
  cv::hconcat(plot.Render(cv::Size(800, 650), title, evaluation::PlotView::kTop),
              plot.Render(cv::Size(800, 650), "side view (x-z)", evaluation::PlotView::kSide),
              image);
  if (!cv::imwrite(path, image)) {
    throw std::runtime_error("cannot write plot " + path);
  }
}

}  // namespace

int main(int argc, char** argv) {
  evaluation::EvaluationOptions options;
  std::string gt_path, est_path;
  std::optional<tools::CommandLine> args;
  try {
    args.emplace(argc, argv,
                 std::set<std::string>{"gt", "est", "align", "max-dt", "gt-to-camera", "gt-to-base",
                                       "gt-to-rectified", "plot", "rpe-delta", "rpe-unit",
                                       "keyframes", "loops", "relocalizations", "poses"},
                 std::set<std::string>{"json", "help"});
    if (args->Flag("help")) {
      std::fputs(kUsage, stdout);
      return 0;
    }
    if (!args->Value("gt") || !args->Value("est") || !args->positional().empty()) {
      throw std::invalid_argument("--gt and --est are required");
    }
    if (args->Value("poses") && args->Flag("json")) {
      throw std::invalid_argument("--poses prints a table: leave out --json");
    }
    if ((args->Value("gt-to-camera") ? 1 : 0) + (args->Value("gt-to-base") ? 1 : 0) +
            (args->Value("gt-to-rectified") ? 1 : 0) >
        1) {
      throw std::invalid_argument(
          "give at most one of --gt-to-camera, --gt-to-base and --gt-to-rectified, not several");
    }
    gt_path = *args->Value("gt");
    est_path = *args->Value("est");
    const auto alignment = evaluation::ParseAlignmentMode(args->ValueOr("align", "se3"));
    if (!alignment) throw std::invalid_argument("--align must be se3, sim3 or none");
    options.alignment = *alignment;
    options.max_dt = args->NumberOr("max-dt", options.max_dt);
    options.rpe_delta.value = args->NumberOr("rpe-delta", options.rpe_delta.value);
    const std::string unit = args->ValueOr("rpe-unit", "frames");
    if (unit != "frames" && unit != "m")
      throw std::invalid_argument("--rpe-unit must be frames or m");
    options.rpe_delta.unit =
        unit == "m" ? evaluation::RpeDelta::Unit::kMeters : evaluation::RpeDelta::Unit::kFrames;
  } catch (const std::invalid_argument& error) {
    std::fprintf(stderr, "evaluate_trajectory: %s\n%s", error.what(), kUsage);
    return 2;
  }

  try {
    evaluation::Trajectory ground_truth = ReadWithWarnings(gt_path);
    if (const auto sensor_yaml = args->Value("gt-to-camera")) {
      const camera::CameraCalibration camera = camera::ReadEurocSensorYaml(*sensor_yaml);
      ground_truth = evaluation::TransformToSensorFrame(ground_truth, camera.T_body_camera);
    }
    if (const auto stereo_yaml = args->Value("gt-to-rectified")) {
      ground_truth = evaluation::TransformToSensorFrame(
          ground_truth,
          camera::StereoRectifier::FromCalibration(camera::ReadStereoCalibrationYaml(*stereo_yaml))
              .T_body_rectified_left());
    }
    if (const auto stereo_yaml = args->Value("gt-to-base")) {
      ground_truth = evaluation::TransformToSensorFrame(
          ground_truth, camera::ReadStereoCalibrationYaml(*stereo_yaml).T_body_base);
    }
    const evaluation::Trajectory estimate = ReadWithWarnings(est_path);
    const evaluation::EvaluationResult result =
        evaluation::EvaluateTrajectory(ground_truth, estimate, options);
    if (args->Flag("json")) {
      PrintJson(result, options);
    } else {
      PrintTable(result, options, gt_path, est_path);
    }
    if (const auto poses_path = args->Value("poses")) {
      // Each pose against the ground truth nearest in time, after the estimate's alignment.
      for (const auto& pose : io::ReadTrajectory(*poses_path)) {
        const auto nearest = std::min_element(ground_truth.begin(), ground_truth.end(),
                                              [&](const auto& a, const auto& b) {
                                                return std::abs(a.timestamp - pose.timestamp) <
                                                       std::abs(b.timestamp - pose.timestamp);
                                              });
        if (nearest == ground_truth.end() ||
            std::abs(nearest->timestamp - pose.timestamp) > options.max_dt) {
          std::printf("pose %.6f: no ground truth within %.3f s\n", pose.timestamp, options.max_dt);
          continue;
        }
        const Eigen::Isometry3d aligned = result.alignment.Apply(pose.pose);
        const double angle =
            Eigen::AngleAxisd(nearest->pose.linear().transpose() * aligned.linear()).angle();
        std::printf("pose %.6f: %.4f m, %.3f deg\n", pose.timestamp,
                    (aligned.translation() - nearest->pose.translation()).norm(),
                    angle * 180.0 / M_PI);
      }
    }
    if (const auto plot_path = args->Value("plot")) {
      const auto keyframes_path = args->Value("keyframes");
      const auto loops_path = args->Value("loops");
      const auto relocalizations_path = args->Value("relocalizations");
      WritePlot(
          result, keyframes_path ? io::ReadTrajectory(*keyframes_path) : evaluation::Trajectory{},
          estimate, loops_path ? ReadTimePairs(*loops_path) : TimePairs{},
          relocalizations_path ? ReadTimePairs(*relocalizations_path) : TimePairs{}, *plot_path);
    }
  } catch (const std::exception& error) {
    std::fprintf(stderr, "evaluate_trajectory: %s\n", error.what());
    return 1;
  }
  return 0;
}
