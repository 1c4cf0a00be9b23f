#include "stereo_fabmap_slam/relocalization/relocalization_options.h"

#include <stdexcept>

namespace stereo_fabmap_slam::relocalization {

void RelocalizerOptions::Visit(io::OptionVisitor& visitor) {
  visitor.Visit("max_candidates", &max_candidates);
  visitor.Visit("neighbours", &neighbours);
  visitor.Visit("match_ratio", &match_ratio);
  io::VisitEnum(visitor, "pnp_kernel", &pnp_kernel, geometry::kPnpKernelNames);
  visitor.Visit("ransac_threshold", &ransac_threshold);
  visitor.Visit("ransac_iterations", &ransac_iterations);
  visitor.Visit("min_ransac_inliers", &min_ransac_inliers);
  visitor.Visit("search_radius", &search_radius);
  visitor.Visit("min_inliers", &min_inliers);
  visitor.Visit("min_inlier_cells", &min_inlier_cells);
  visitor.Visit("attempt_every_n_frames", &attempt_every_n_frames);
  visitor.Visit("confirm_distance", &confirm_distance);
  visitor.Visit("confirm_translation", &confirm_translation);
  visitor.Visit("confirm_rotation_deg", &confirm_rotation_deg);
  visitor.Visit("translation_sigma", &translation_sigma);
  visitor.Visit("rotation_sigma_deg", &rotation_sigma_deg);
}

void RelocalizerOptions::Validate() const {
  if (max_candidates < 1) throw std::invalid_argument("relocalization.max_candidates must be >= 1");
  if (neighbours < 0) throw std::invalid_argument("relocalization.neighbours must be >= 0");
  if (!(match_ratio > 0 && match_ratio <= 1)) {
    throw std::invalid_argument("relocalization.match_ratio must lie in (0, 1]");
  }
  if (!(ransac_threshold > 0) || ransac_iterations < 1) {
    throw std::invalid_argument("relocalization RANSAC threshold and iterations must be > 0");
  }
  if (!(search_radius > 0)) throw std::invalid_argument("relocalization.search_radius must be > 0");
  if (min_ransac_inliers < 6 || min_inliers < min_ransac_inliers) {
    throw std::invalid_argument("relocalization: need 6 <= min_ransac_inliers <= min_inliers");
  }
  if (min_inlier_cells < 1 || min_inlier_cells > 16) {
    throw std::invalid_argument("relocalization.min_inlier_cells must lie in [1, 16]");
  }
  if (attempt_every_n_frames < 1) {
    throw std::invalid_argument("relocalization.attempt_every_n_frames must be >= 1");
  }
  if (!(confirm_distance >= 0) || !(confirm_translation > 0) || !(confirm_rotation_deg > 0)) {
    throw std::invalid_argument(
        "relocalization: need confirm_distance >= 0, confirm_translation and "
        "confirm_rotation_deg > 0");
  }
  if (!(translation_sigma > 0) || !(rotation_sigma_deg > 0)) {
    throw std::invalid_argument("relocalization sigmas must be > 0");
  }
}

}  // namespace stereo_fabmap_slam::relocalization
