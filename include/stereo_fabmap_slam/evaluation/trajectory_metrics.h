#pragma once

#include <cstddef>
#include <vector>

#include "stereo_fabmap_slam/evaluation/alignment.h"
#include "stereo_fabmap_slam/evaluation/trajectory.h"

namespace stereo_fabmap_slam::evaluation {

struct ErrorStatistics {
  double rmse = 0, mean = 0, median = 0, max = 0;
  std::size_t count = 0;
};

// RMSE, mean, median (mean of the middle two for an even count) and max of a list of errors.
ErrorStatistics Summarize(std::vector<double> errors);

// The step between the two poses of a relative pose error.
struct RpeDelta {
  enum class Unit { kFrames, kMeters };
  double value = 1.0;
  Unit unit = Unit::kFrames;
};

// Absolute trajectory error: distances between corresponding positions (evo_ape's "translation
// part"). Both trajectories must be matched pose by pose and already expressed in one frame.
ErrorStatistics ComputeAbsoluteTrajectoryError(const Trajectory& reference,
                                               const Trajectory& estimate);

struct RelativePoseError {
  ErrorStatistics translation;   // [m]
  ErrorStatistics rotation_deg;  // [deg]
};

// Relative pose error. For every matched pose i, j is i + delta frames, or the first later pose
// at least delta metres further along the reference path. With Q the reference and P the
// estimate, E_ij = (Q_i^-1 Q_j)^-1 (P_i^-1 P_j); the errors are |translation(E_ij)| and the
// rotation angle of E_ij. Every i that has such a j counts (evo_rpe with --all_pairs).
RelativePoseError ComputeRelativePoseError(const Trajectory& reference, const Trajectory& estimate,
                                           const RpeDelta& delta);

struct EvaluationOptions {
  double max_dt = 0.01;  // [s] association limit
  AlignmentMode alignment = AlignmentMode::kSE3;
  RpeDelta rpe_delta;
};

struct EvaluationResult {
  std::size_t estimated_poses = 0;
  std::size_t matched = 0;
  Similarity3 alignment;         // maps the estimate into the reference frame
  Trajectory matched_reference;  // reference poses that have a match
  Trajectory aligned_estimate;   // their matches, moved by `alignment`
  ErrorStatistics ate;
  RelativePoseError rpe;
};

// Associates by time, aligns the estimate to the reference by its positions (evo_ape -a: SE(3)
// Umeyama alignment), and computes ATE and RPE on the matched poses. Throws std::invalid_argument
// if fewer than 3 poses match (2 for kNone).
EvaluationResult EvaluateTrajectory(const Trajectory& reference, const Trajectory& estimate,
                                    const EvaluationOptions& options);

}  // namespace stereo_fabmap_slam::evaluation
