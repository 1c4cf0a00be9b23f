#include "stereo_fabmap_slam/backend/backend_options.h"

#include <cmath>
#include <sstream>
#include <stdexcept>

namespace stereo_fabmap_slam::backend {
namespace {

void RequirePositive(const char* key, double value) {
  // Written to reject NaN as well: it compares false.
  if (!(value > 0) || !std::isfinite(value)) {
    std::ostringstream message;
    message << "pose_graph." << key << " must be a finite number > 0, got " << value;
    throw std::invalid_argument(message.str());
  }
}

}  // namespace

void BundleAdjustmentOptions::Visit(io::OptionVisitor& visitor) {
  visitor.Visit("window", &window);
  visitor.Visit("fixed_keyframes", &fixed_keyframes);
  visitor.Visit("iterations", &iterations);
  visitor.Visit("converged_step_decrease", &converged_step_decrease);
  visitor.Visit("rounds", &rounds);
  visitor.Visit("sigma", &sigma);
  visitor.Visit("threads", &threads);
  visitor.Visit("step_covariances", &step_covariances);
}

void BundleAdjustmentOptions::Validate() const {
  if (window < 2) throw std::invalid_argument("backend.window must be >= 2");
  if (fixed_keyframes < 1 || fixed_keyframes >= window) {
    throw std::invalid_argument("backend.fixed_keyframes must lie in [1, window)");
  }
  if (iterations < 1 || rounds < 1 || threads < 1) {
    throw std::invalid_argument("backend iterations, rounds and threads must be >= 1");
  }
  if (!(sigma > 0)) throw std::invalid_argument("backend.sigma must be > 0");
  if (!(converged_step_decrease >= 0) || !std::isfinite(converged_step_decrease)) {
    throw std::invalid_argument("backend.converged_step_decrease must be a finite number >= 0");
  }
}

void PoseGraphOptions::Visit(io::OptionVisitor& visitor) {
  visitor.Visit("odometry_translation_sigma", &odometry_translation_sigma);
  visitor.Visit("odometry_rotation_sigma_deg", &odometry_rotation_sigma_deg);
  visitor.Visit("odometry_covariance_scale", &odometry_covariance_scale);
  visitor.Visit("odometry_covariance_plus_fixed", &odometry_covariance_plus_fixed);
  visitor.Visit("loop_loss_scale", &loop_loss_scale);
  visitor.Visit("iterations", &iterations);
  visitor.Visit("consistent_loop_chi2", &consistent_loop_chi2);
  visitor.Visit("local_keyframes", &local_keyframes);
  visitor.Visit("gap_max_seconds", &gap_max_seconds);
  visitor.Visit("gap_translation_sigma_per_second", &gap_translation_sigma_per_second);
  visitor.Visit("gap_rotation_sigma_deg_per_second", &gap_rotation_sigma_deg_per_second);
  visitor.Visit("gap_chi2", &gap_chi2);
}

void PoseGraphOptions::Validate() const {
  RequirePositive("odometry_translation_sigma", odometry_translation_sigma);
  RequirePositive("odometry_rotation_sigma_deg", odometry_rotation_sigma_deg);
  if (!(odometry_covariance_scale >= 0))
    throw std::invalid_argument("pose_graph.odometry_covariance_scale must be >= 0");
  RequirePositive("loop_loss_scale", loop_loss_scale);
  if (iterations < 1) {
    throw std::invalid_argument("pose_graph.iterations must be >= 1, got " +
                                std::to_string(iterations));
  }
  RequirePositive("consistent_loop_chi2", consistent_loop_chi2);
  if (local_keyframes < 0) {
    throw std::invalid_argument("pose_graph.local_keyframes must be >= 0, got " +
                                std::to_string(local_keyframes));
  }
  // gap_max_seconds 0 turns gaps off.
  if (!(gap_max_seconds >= 0) || !std::isfinite(gap_max_seconds)) {
    throw std::invalid_argument("pose_graph.gap_max_seconds must be a finite number >= 0");
  }
  RequirePositive("gap_translation_sigma_per_second", gap_translation_sigma_per_second);
  RequirePositive("gap_rotation_sigma_deg_per_second", gap_rotation_sigma_deg_per_second);
  RequirePositive("gap_chi2", gap_chi2);
}

void GlobalRefinementOptions::Visit(io::OptionVisitor& visitor) {
  visitor.Visit("after_loop_closing", &after_loop_closing);
  visitor.Visit("at_end", &at_end);
  visitor.Visit("iterations", &iterations);
  visitor.Visit("rounds", &rounds);
  visitor.Visit("odometry_edge_below_shared_points", &odometry_edge_below_shared_points);
  visitor.Visit("loop_information_scale", &loop_information_scale);
  visitor.Visit("fuse_loop_points", &fuse_loop_points);
  visitor.Visit("fuse_max_distance", &fuse_max_distance);
  visitor.Visit("threads", &threads);
}

void GlobalRefinementOptions::Validate() const {
  if (iterations < 1 || rounds < 1 || threads < 1) {
    throw std::invalid_argument("global_refinement iterations, rounds and threads must be >= 1");
  }
  if (odometry_edge_below_shared_points < 0) {
    throw std::invalid_argument("global_refinement.odometry_edge_below_shared_points must be >= 0");
  }
  if (!(fuse_max_distance > 0)) {
    throw std::invalid_argument("global_refinement.fuse_max_distance must be > 0");
  }
  if (!(loop_information_scale > 0)) {
    throw std::invalid_argument("global_refinement.loop_information_scale must be > 0");
  }
}

}  // namespace stereo_fabmap_slam::backend
