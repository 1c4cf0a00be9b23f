#include "stereo_fabmap_slam/evaluation/trajectory_metrics.h"

#include <algorithm>
#include <cmath>
#include <numeric>
#include <stdexcept>
#include <string>

#include "stereo_fabmap_slam/evaluation/association.h"

namespace stereo_fabmap_slam::evaluation {
namespace {

double RotationAngleDegrees(const Eigen::Matrix3d& rotation) {
  // Angle from the trace, clamped against rounding just outside [-1, 1].
  const double cosine = std::clamp((rotation.trace() - 1.0) / 2.0, -1.0, 1.0);
  return std::acos(cosine) * 180.0 / M_PI;
}

void RequireSameLength(const Trajectory& reference, const Trajectory& estimate) {
  if (reference.size() != estimate.size()) {
    throw std::invalid_argument("reference and estimate must be matched pose by pose");
  }
}

// Index of the pose that ends step `delta` from pose i, or reference.size() if none does.
std::size_t StepEnd(const Trajectory& reference, std::size_t i, const RpeDelta& delta) {
  if (delta.unit == RpeDelta::Unit::kFrames) {
    return i + static_cast<std::size_t>(delta.value);
  }
  double path = 0;
  for (std::size_t j = i + 1; j < reference.size(); ++j) {
    path += (reference[j].pose.translation() - reference[j - 1].pose.translation()).norm();
    if (path >= delta.value) return j;
  }
  return reference.size();
}

}  // namespace

ErrorStatistics Summarize(std::vector<double> errors) {
  ErrorStatistics stats;
  stats.count = errors.size();
  if (errors.empty()) return stats;
  const double n = static_cast<double>(errors.size());
  stats.mean = std::accumulate(errors.begin(), errors.end(), 0.0) / n;
  stats.rmse = std::sqrt(std::inner_product(errors.begin(), errors.end(), errors.begin(), 0.0) / n);
  stats.max = *std::max_element(errors.begin(), errors.end());
  const std::size_t middle = errors.size() / 2;
  std::nth_element(errors.begin(), errors.begin() + middle, errors.end());
  stats.median = errors[middle];
  if (errors.size() % 2 == 0) {
    stats.median =
        0.5 * (stats.median + *std::max_element(errors.begin(), errors.begin() + middle));
  }
  return stats;
}

ErrorStatistics ComputeAbsoluteTrajectoryError(const Trajectory& reference,
                                               const Trajectory& estimate) {
  RequireSameLength(reference, estimate);
  std::vector<double> errors;
  errors.reserve(reference.size());
  for (std::size_t i = 0; i < reference.size(); ++i) {
    errors.push_back((reference[i].pose.translation() - estimate[i].pose.translation()).norm());
  }
  return Summarize(std::move(errors));
}

RelativePoseError ComputeRelativePoseError(const Trajectory& reference, const Trajectory& estimate,
                                           const RpeDelta& delta) {
  RequireSameLength(reference, estimate);
  if (!(delta.value > 0) ||
      (delta.unit == RpeDelta::Unit::kFrames && delta.value != std::floor(delta.value))) {
    throw std::invalid_argument("RPE delta must be a positive number (whole for frames)");
  }
  std::vector<double> translation_errors, rotation_errors;
  for (std::size_t i = 0; i < reference.size(); ++i) {
    const std::size_t j = StepEnd(reference, i, delta);
    if (j >= reference.size()) break;  // later i have no end either
    const Eigen::Isometry3d reference_step = reference[i].pose.inverse() * reference[j].pose;
    const Eigen::Isometry3d estimate_step = estimate[i].pose.inverse() * estimate[j].pose;
    const Eigen::Isometry3d error = reference_step.inverse() * estimate_step;
    translation_errors.push_back(error.translation().norm());
    rotation_errors.push_back(RotationAngleDegrees(error.linear()));
  }
  return {Summarize(std::move(translation_errors)), Summarize(std::move(rotation_errors))};
}

EvaluationResult EvaluateTrajectory(const Trajectory& reference, const Trajectory& estimate,
                                    const EvaluationOptions& options) {
  EvaluationResult result;
  result.estimated_poses = estimate.size();
  const std::vector<AssociatedPair> pairs =
      AssociateByTimestamp(reference, estimate, options.max_dt);
  result.matched = pairs.size();
  const std::size_t needed = options.alignment == AlignmentMode::kNone ? 2 : 3;
  if (pairs.size() < needed) {
    // Named from the side that searched, the shorter (see AssociateByTimestamp).
    const bool estimate_longer = estimate.size() > reference.size();
    throw std::invalid_argument(
        "only " + std::to_string(pairs.size()) + " of " +
        std::to_string(estimate_longer ? reference.size() : estimate.size()) +
        (estimate_longer ? " reference poses have an estimated pose within "
                         : " estimated poses have a reference pose within ") +
        std::to_string(options.max_dt) +
        " s; check the timestamps (seconds in both files?) or raise --max-dt");
  }
  std::vector<Eigen::Vector3d> reference_positions, estimate_positions;
  Trajectory matched_estimate;
  for (const AssociatedPair& pair : pairs) {
    result.matched_reference.push_back(reference[pair.reference]);
    matched_estimate.push_back(estimate[pair.estimate]);
    reference_positions.push_back(reference[pair.reference].pose.translation());
    estimate_positions.push_back(estimate[pair.estimate].pose.translation());
  }
  result.alignment = AlignPositions(reference_positions, estimate_positions, options.alignment);
  for (const StampedPose& pose : matched_estimate) {
    result.aligned_estimate.push_back({pose.timestamp, result.alignment.Apply(pose.pose)});
  }
  result.ate = ComputeAbsoluteTrajectoryError(result.matched_reference, result.aligned_estimate);
  result.rpe = ComputeRelativePoseError(result.matched_reference, result.aligned_estimate,
                                        options.rpe_delta);
  return result;
}

}  // namespace stereo_fabmap_slam::evaluation
