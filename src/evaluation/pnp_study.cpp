#include "stereo_fabmap_slam/evaluation/pnp_study.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <map>
#include <stdexcept>
#include <tuple>

#include <opencv2/core.hpp>

#include "stereo_fabmap_slam/features/descriptor_matching.h"

namespace stereo_fabmap_slam::evaluation {
namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

const char* KernelName(geometry::PnpKernel kernel) {
  for (const auto& entry : geometry::kPnpKernelNames) {
    if (entry.value == kernel) return entry.name;
  }
  return "?";
}

int KernelRank(geometry::PnpKernel kernel) {
  int rank = 0;
  for (const auto& entry : geometry::kPnpKernelNames) {
    if (entry.value == kernel) return rank;
    ++rank;
  }
  return rank;
}

// Mean and sample standard deviation; NaN for no values, a deviation of 0 for one.
std::pair<double, double> MeanAndDeviation(const std::vector<double>& values) {
  if (values.empty()) return {kNaN, kNaN};
  double sum = 0;
  for (const double value : values) sum += value;
  const double mean = sum / static_cast<double>(values.size());
  if (values.size() == 1) return {mean, 0.0};
  double squares = 0;
  for (const double value : values) squares += (value - mean) * (value - mean);
  return {mean, std::sqrt(squares / static_cast<double>(values.size() - 1))};
}

PnpStatistics Pool(const std::vector<const PnpTrial*>& trials) {
  PnpStatistics row;
  row.kernel = trials.front()->kernel;
  row.refined = trials.front()->refined;
  std::vector<double> translation, rotation, time;
  for (const PnpTrial* trial : trials) {
    ++row.trials;
    time.push_back(trial->time_ms);
    if (!trial->success) continue;
    ++row.successes;
    translation.push_back(trial->error.translation_m);
    rotation.push_back(trial->error.rotation_deg);
  }
  std::tie(row.translation_error_mean_m, row.translation_error_std_m) =
      MeanAndDeviation(translation);
  std::tie(row.rotation_error_mean_deg, row.rotation_error_std_deg) = MeanAndDeviation(rotation);
  std::tie(row.time_mean_ms, row.time_std_ms) = MeanAndDeviation(time);
  return row;
}

// Groups trials by kernel, refined and a bin index, in the documented row order.
std::vector<PnpStatistics> Group(const std::vector<PnpTrial>& trials, double bin_width) {
  std::map<std::tuple<int, bool, long>, std::vector<const PnpTrial*>> groups;
  for (const PnpTrial& trial : trials) {
    const long bin =
        bin_width > 0 ? static_cast<long>(std::floor(trial.distance_m / bin_width)) : 0;
    groups[{KernelRank(trial.kernel), trial.refined, bin}].push_back(&trial);
  }
  std::vector<PnpStatistics> rows;
  for (const auto& [key, members] : groups) {
    PnpStatistics row = Pool(members);
    row.distance_m =
        bin_width > 0 ? (static_cast<double>(std::get<2>(key)) + 0.5) * bin_width : kNaN;
    rows.push_back(row);
  }
  return rows;
}

// RFC 4180 quoting for a free-text field (a sequence folder's name).
std::string CsvField(const std::string& text) {
  if (text.find_first_of(",\"\n\r") == std::string::npos) return text;
  std::string quoted = "\"";
  for (const char c : text) {
    if (c == '"') quoted += '"';
    quoted += c;
  }
  return quoted + "\"";
}

std::string Number(double value) {
  char buffer[32];
  std::snprintf(buffer, sizeof buffer, "%.6g", value);
  return buffer;
}

}  // namespace

void PnpStudyOptions::Validate() const {
  if (!(match_ratio > 0 && match_ratio <= 1)) {
    throw std::invalid_argument("PnP study: match_ratio must lie in (0, 1]");
  }
  if (!(ransac.reprojection_threshold > 0) || ransac.max_iterations < 1 ||
      !(ransac.confidence > 0 && ransac.confidence < 1)) {
    throw std::invalid_argument(
        "PnP study: RANSAC needs a threshold > 0, iterations >= 1 and a confidence in (0, 1)");
  }
  if (min_inliers < 3) throw std::invalid_argument("PnP study: min_inliers must be >= 3");
  refinement.Validate();
}

PoseError ComparePoses(const Eigen::Isometry3d& estimated_T_camera_reference,
                       const Eigen::Isometry3d& true_T_camera_reference) {
  // In the reference frame, as the relocalizer reports poses (T_keyframe_camera).
  const Eigen::Isometry3d difference =
      true_T_camera_reference * estimated_T_camera_reference.inverse();
  PoseError error;
  error.translation_m = difference.translation().norm();
  // The angle from the trace, clamped: AngleAxis of a rotation a hair from identity can lose
  // accuracy that the < 1e-6 degree checks of exact data need.
  const double cosine = std::clamp((difference.linear().trace() - 1.0) / 2.0, -1.0, 1.0);
  const Eigen::Matrix3d skew = difference.linear() - difference.linear().transpose();
  const double sine = 0.5 * Eigen::Vector3d(skew(2, 1), skew(0, 2), skew(1, 0)).norm();
  error.rotation_deg = std::atan2(sine, cosine) * 180.0 / M_PI;
  return error;
}

geometry::PointMatches MatchToReference(const features::StereoFeatures& reference,
                                        const features::StereoFeatures& test, int descriptor_norm,
                                        double max_descriptor_distance, double match_ratio) {
  std::vector<Eigen::Vector3d> points;
  std::vector<int> rows;
  for (std::size_t i = 0; i < reference.size(); ++i) {
    if (!reference.HasDepth(i)) continue;
    points.push_back(reference.points[i]);
    rows.push_back(static_cast<int>(i));
  }
  cv::Mat descriptors;
  if (!rows.empty()) {
    descriptors.create(static_cast<int>(rows.size()), reference.descriptors.cols,
                       reference.descriptors.type());
    for (std::size_t k = 0; k < rows.size(); ++k) {
      reference.descriptors.row(rows[k]).copyTo(descriptors.row(static_cast<int>(k)));
    }
  }
  return geometry::MatchedPoints(
      test.keypoints, test.u_right, test.points, points,
      features::RatioTestMatches(test.descriptors, descriptors, descriptor_norm,
                                 max_descriptor_distance, match_ratio));
}

std::vector<PnpTrial> RunPnpKernels(const geometry::PointMatches& matches,
                                    const geometry::StereoCamera& camera,
                                    const Eigen::Isometry3d& true_T_camera_reference,
                                    const std::vector<geometry::PnpKernel>& kernels,
                                    const PnpStudyOptions& options, const Clock& clock) {
  options.Validate();
  // The test camera's position in the reference frame.
  const double distance = true_T_camera_reference.inverse().translation().norm();
  const int match_count = static_cast<int>(matches.correspondences.size());
  std::vector<PnpTrial> trials;
  for (const geometry::PnpKernel kernel : kernels) {
    PnpTrial plain;
    plain.kernel = kernel;
    plain.distance_m = distance;
    plain.matches = match_count;
    geometry::PnpRansacOptions ransac = options.ransac;
    ransac.kernel = kernel;

    const double start = clock();
    geometry::PnpResult estimate;
    try {
      // No prior: the reference pose seeds ITERATIVE, as the relocalizer's identity does.
      estimate = geometry::SolvePnpRansac(matches.correspondences, camera, ransac,
                                          Eigen::Isometry3d::Identity());
    } catch (const cv::Exception&) {
      estimate = geometry::PnpResult{};
    }
    plain.time_ms = clock() - start;
    plain.inliers = static_cast<int>(estimate.inliers.size());
    plain.success = estimate.success && plain.inliers >= options.min_inliers;
    if (plain.success) plain.error = ComparePoses(estimate.T_camera_world, true_T_camera_reference);

    PnpTrial refined = plain;
    refined.refined = true;
    refined.success = false;
    refined.error = PoseError{};
    if (plain.success) {
      std::vector<bool> initial(matches.observations.size(), false);
      for (const int i : estimate.inliers) initial[static_cast<std::size_t>(i)] = true;
      const double refine_start = clock();
      const geometry::PoseRefinement pose = geometry::RefinePose(
          matches.observations, camera, estimate.T_camera_world, options.refinement, &initial);
      refined.time_ms += clock() - refine_start;
      refined.inliers = pose.inliers;
      refined.success = pose.inliers >= options.min_inliers;
      if (refined.success) {
        refined.error = ComparePoses(pose.T_camera_world, true_T_camera_reference);
      }
    }
    trials.push_back(plain);
    trials.push_back(refined);
  }
  return trials;
}

std::vector<geometry::PnpKernel> AllPnpKernels() {
  std::vector<geometry::PnpKernel> kernels;
  for (const auto& entry : geometry::kPnpKernelNames) kernels.push_back(entry.value);
  return kernels;
}

std::vector<PnpStatistics> AggregatePnpTrials(const std::vector<PnpTrial>& trials,
                                              double bin_width) {
  if (!(bin_width > 0)) throw std::invalid_argument("PnP study: the bin width must be > 0");
  return Group(trials, bin_width);
}

std::vector<PnpStatistics> SummarizePnpTrials(const std::vector<PnpTrial>& trials) {
  return Group(trials, 0.0);
}

void WritePnpCsvHeader(std::ostream& out, bool with_distance) {
  out << "sequence,kernel,refined," << (with_distance ? "distance_m," : "")
      << "trials,successes,translation_error_mean_m,translation_error_std_m,"
         "rotation_error_mean_deg,rotation_error_std_deg,time_mean_ms,time_std_ms\n";
}

void WritePnpCsvRows(std::ostream& out, const std::string& sequence,
                     const std::vector<PnpStatistics>& rows, bool with_distance) {
  for (const PnpStatistics& row : rows) {
    out << CsvField(sequence) << ',' << KernelName(row.kernel) << ',' << (row.refined ? 1 : 0)
        << ',';
    if (with_distance) out << Number(row.distance_m) << ',';
    out << row.trials << ',' << row.successes << ',' << Number(row.translation_error_mean_m) << ','
        << Number(row.translation_error_std_m) << ',' << Number(row.rotation_error_mean_deg) << ','
        << Number(row.rotation_error_std_deg) << ',' << Number(row.time_mean_ms) << ','
        << Number(row.time_std_ms) << '\n';
  }
}

void PrintPnpTable(std::ostream& out, const std::string& title,
                   const std::vector<PnpStatistics>& rows, bool with_distance) {
  out << title << '\n';
  char line[200];
  std::snprintf(line, sizeof line, "%-10s %-7s %s%7s %8s  %-19s %-19s %-17s\n", "kernel", "refined",
                with_distance ? "distance m " : "", "trials", "success", "translation cm",
                "rotation deg", "time ms");
  out << line;
  for (const PnpStatistics& row : rows) {
    char distance[16] = "";
    if (with_distance) std::snprintf(distance, sizeof distance, "%10.2f ", row.distance_m);
    std::snprintf(line, sizeof line,
                  "%-10s %-7s %s%7d %7.1f%%  %8.2f +- %-7.2f %8.3f +- %-7.3f %7.2f +- %-7.2f\n",
                  KernelName(row.kernel), row.refined ? "yes" : "no", distance, row.trials,
                  100.0 * row.success_fraction(), 100.0 * row.translation_error_mean_m,
                  100.0 * row.translation_error_std_m, row.rotation_error_mean_deg,
                  row.rotation_error_std_deg, row.time_mean_ms, row.time_std_ms);
    out << line;
  }
}

}  // namespace stereo_fabmap_slam::evaluation
