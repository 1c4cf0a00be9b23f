#include "stereo_fabmap_slam/odometry/odometry_options.h"

#include <stdexcept>

namespace stereo_fabmap_slam::odometry {

void KeyframePolicyOptions::Visit(io::OptionVisitor& visitor) {
  visitor.Visit("min_tracked_ratio", &min_tracked_ratio);
  visitor.Visit("min_tracked_points", &min_tracked_points);
  visitor.Visit("max_translation", &max_translation);
  visitor.Visit("max_rotation_deg", &max_rotation_deg);
  visitor.Visit("max_interval", &max_interval);
  visitor.Visit("min_interval", &min_interval);
}

void KeyframePolicyOptions::Validate() const {
  if (!(min_tracked_ratio >= 0 && min_tracked_ratio <= 1)) {
    throw std::invalid_argument("keyframes.min_tracked_ratio must lie in [0, 1]");
  }
  if (min_tracked_points < 0)
    throw std::invalid_argument("keyframes.min_tracked_points must be >= 0");
  if (!(max_translation > 0) || !(max_rotation_deg > 0) || !(max_interval > 0)) {
    throw std::invalid_argument(
        "keyframes: max_translation, max_rotation_deg, max_interval must be > 0");
  }
  if (!(min_interval >= 0 && min_interval < max_interval)) {
    throw std::invalid_argument("keyframes.min_interval must lie in [0, max_interval)");
  }
}

void TrackerOptions::Visit(io::OptionVisitor& visitor) {
  visitor.Visit("search_radius", &search_radius);
  visitor.Visit("search_radius_fine", &search_radius_fine);
  visitor.Visit("match_ratio", &match_ratio);
  io::VisitEnum(visitor, "pnp_kernel", &pnp_kernel, geometry::kPnpKernelNames);
  visitor.Visit("ransac_threshold", &ransac_threshold);
  visitor.Visit("ransac_iterations", &ransac_iterations);
  visitor.Visit("min_inliers_ok", &min_inliers_ok);
  visitor.Visit("min_inliers_weak", &min_inliers_weak);
  visitor.Visit("min_map_points", &min_map_points);
  visitor.Visit("local_keyframes", &local_keyframes);
  visitor.Visit("max_prediction_gap", &max_prediction_gap);
  visitor.Visit("max_time_lost", &max_time_lost);
  visitor.Visit("max_descriptor_jump", &max_descriptor_jump);
  visitor.Visit("max_descriptor_jump_deg", &max_descriptor_jump_deg);
  visitor.Visit("jump_min_inlier_cells", &jump_min_inlier_cells);
  visitor.Visit("parallel", &parallel);
  visitor.Visit("queued_pairs", &queued_pairs);
  visitor.Visit("catch_up_gap", &catch_up_gap);
  visitor.Visit("refinement_sigma", &refinement.sigma);
  visitor.Visit("refinement_rounds", &refinement.rounds);
  visitor.Visit("refinement_iterations", &refinement.iterations);
}

void TrackerOptions::Validate() const {
  if (!(search_radius > 0 && search_radius_fine > 0)) {
    throw std::invalid_argument("tracker search radii must be > 0");
  }
  if (!(match_ratio > 0 && match_ratio <= 1)) {
    throw std::invalid_argument("tracker.match_ratio must lie in (0, 1]");
  }
  if (!(ransac_threshold > 0) || ransac_iterations < 1) {
    throw std::invalid_argument("tracker RANSAC threshold and iterations must be > 0");
  }
  if (min_inliers_weak < 6 || min_inliers_ok < min_inliers_weak) {
    throw std::invalid_argument("tracker: need 6 <= min_inliers_weak <= min_inliers_ok");
  }
  if (!(max_prediction_gap > 0))
    throw std::invalid_argument("tracker.max_prediction_gap must be > 0");
  if (!(max_time_lost >= 0)) throw std::invalid_argument("tracker.max_time_lost must be >= 0");
  if (!(max_descriptor_jump > 0 && max_descriptor_jump_deg > 0) || jump_min_inlier_cells < 1 ||
      jump_min_inlier_cells > 16) {
    throw std::invalid_argument(
        "tracker: max_descriptor_jump and max_descriptor_jump_deg > 0, jump_min_inlier_cells in "
        "[1, 16]");
  }
  if (queued_pairs < 1) throw std::invalid_argument("tracker.queued_pairs must be >= 1");
  if (!(catch_up_gap >= 0)) throw std::invalid_argument("tracker.catch_up_gap must be >= 0");
  if (min_map_points < 3 || local_keyframes < 1) {
    throw std::invalid_argument("tracker: min_map_points >= 3 and local_keyframes >= 1");
  }
  refinement.Validate();
}

}  // namespace stereo_fabmap_slam::odometry
