#include "stereo_fabmap_slam/evaluation/relocalization_recall.h"

#include <algorithm>
#include <cmath>

namespace stereo_fabmap_slam::evaluation {

double VisibleFraction(const std::vector<Eigen::Vector3d>& keyframe_points,
                       const Eigen::Isometry3d& T_view_keyframe,
                       const geometry::StereoCamera& camera) {
  if (keyframe_points.empty()) return 0.0;
  int visible = 0;
  for (const Eigen::Vector3d& point : keyframe_points) {
    const Eigen::Vector3d in_view = T_view_keyframe * point;
    // A point on or behind the image plane projects nowhere meaningful.
    if (in_view.z() <= 1e-6) continue;
    const double u = camera.fx * in_view.x() / in_view.z() + camera.cx;
    const double v = camera.fy * in_view.y() / in_view.z() + camera.cy;
    // Pixel centres are at integers: the image covers [-0.5, size - 0.5).
    if (u >= -0.5 && v >= -0.5 && u < camera.size.width - 0.5 && v < camera.size.height - 0.5)
      ++visible;
  }
  return static_cast<double>(visible) / static_cast<double>(keyframe_points.size());
}

double RelocalizationRecall(const std::vector<RelocalizationTrial>& trials, double tau,
                            double max_error_m) {
  int relevant = 0, found = 0;
  for (const RelocalizationTrial& trial : trials) {
    if (trial.relevance < tau) continue;
    ++relevant;
    found += trial.estimated && trial.error_m <= max_error_m ? 1 : 0;
  }
  return relevant > 0 ? static_cast<double>(found) / relevant : 0.0;
}

RelocalizationSummary SummarizeRelocalization(const std::vector<RelocalizationTrial>& trials,
                                              double tau, double max_error_m) {
  RelocalizationSummary summary;
  summary.test_frames = static_cast<int>(trials.size());
  std::vector<double> errors;
  for (const RelocalizationTrial& trial : trials) {
    summary.relevant_frames += trial.relevance >= tau ? 1 : 0;
    if (!trial.estimated) continue;
    errors.push_back(trial.error_m);
    summary.wrong_estimates += trial.error_m > max_error_m ? 1 : 0;
  }
  summary.estimated_frames = static_cast<int>(errors.size());
  summary.recall = RelocalizationRecall(trials, tau, max_error_m);
  if (errors.empty()) {
    summary.error_median_m = std::nan("");
    return summary;
  }
  summary.error_below_10cm_fraction =
      static_cast<double>(
          std::count_if(errors.begin(), errors.end(), [](double error) { return error < 0.1; })) /
      static_cast<double>(errors.size());
  std::sort(errors.begin(), errors.end());
  const std::size_t middle = errors.size() / 2;
  summary.error_median_m =
      errors.size() % 2 == 1 ? errors[middle] : 0.5 * (errors[middle - 1] + errors[middle]);
  return summary;
}

}  // namespace stereo_fabmap_slam::evaluation
