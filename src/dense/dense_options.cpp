#include "stereo_fabmap_slam/dense/dense_options.h"

#include <cmath>
#include <stdexcept>
#include <string>

namespace stereo_fabmap_slam::dense {

void StereoDepthOptions::Visit(io::OptionVisitor& visitor) {
  visitor.Visit("disparities", &disparities);
  visitor.Visit("block_size", &block_size);
  visitor.Visit("uniqueness", &uniqueness);
  visitor.Visit("left_right_max_difference", &left_right_max_difference);
  visitor.Visit("speckle_window", &speckle_window);
  visitor.Visit("speckle_range", &speckle_range);
  visitor.Visit("min_texture", &min_texture);
  visitor.Visit("max_depth", &max_depth);
  visitor.Visit("refinement_window", &refinement_window);
  visitor.Visit("matching_scale", &matching_scale);
  visitor.Visit("refinement_steps", &refinement_steps);
  visitor.Visit("smoothing_window", &smoothing_window);
  visitor.Visit("smoothing_agreement", &smoothing_agreement);
  visitor.Visit("edge_jump", &edge_jump);
  visitor.Visit("edge_radius", &edge_radius);
}

void StereoDepthOptions::Validate() const {
  const std::string section = std::string(kSection) + ".";
  if (disparities < 16 || disparities % 16 != 0) {
    throw std::invalid_argument(section + "disparities must be a positive multiple of 16, got " +
                                std::to_string(disparities));
  }
  if (block_size < 1 || block_size % 2 == 0) {
    throw std::invalid_argument(section + "block_size must be odd and positive, got " +
                                std::to_string(block_size));
  }
  if (uniqueness < 0 || left_right_max_difference < 0 || speckle_window < 0 || speckle_range < 0) {
    throw std::invalid_argument(section +
                                "uniqueness, left_right_max_difference, speckle_window and "
                                "speckle_range must not be negative");
  }
  if (!(min_texture >= 0) || !std::isfinite(min_texture)) {
    throw std::invalid_argument(section + "min_texture must be a finite number >= 0");
  }
  if (!(max_depth > 0)) throw std::invalid_argument(section + "max_depth must be > 0");
  if (refinement_window != 0 && (refinement_window < 3 || refinement_window % 2 == 0)) {
    throw std::invalid_argument(section +
                                "refinement_window must be 0 (none) or odd and >= 3, got " +
                                std::to_string(refinement_window));
  }
  if (matching_scale != 1 && matching_scale != 2) {
    throw std::invalid_argument(section + "matching_scale must be 1 (full resolution) or 2, got " +
                                std::to_string(matching_scale));
  }
  if (matching_scale != 1 && refinement_window == 0) {
    throw std::invalid_argument(section +
                                "matching_scale 2 needs the sub-pixel refinement "
                                "(refinement_window > 0): the half-resolution disparities are "
                                "only a start");
  }
  if (smoothing_window != 0 && (smoothing_window < 3 || smoothing_window % 2 == 0)) {
    throw std::invalid_argument(section +
                                "smoothing_window must be 0 (none) or odd and >= 3, got " +
                                std::to_string(smoothing_window));
  }
  if (!(smoothing_agreement > 0) || !std::isfinite(smoothing_agreement)) {
    throw std::invalid_argument(section + "smoothing_agreement must be a finite number > 0");
  }
  if (!(edge_jump >= 0) || !std::isfinite(edge_jump)) {
    throw std::invalid_argument(section + "edge_jump must be a finite number >= 0 (0: none)");
  }
  if (edge_radius < 0) {
    throw std::invalid_argument(section + "edge_radius must be >= 0, got " +
                                std::to_string(edge_radius));
  }
  if (refinement_steps < 1) {
    throw std::invalid_argument(section + "refinement_steps must be >= 1, got " +
                                std::to_string(refinement_steps));
  }
}

void FusionOptions::Visit(io::OptionVisitor& visitor) {
  visitor.Visit("voxel_size", &voxel_size);
  visitor.Visit("truncation", &truncation);
  visitor.Visit("block_resolution", &block_resolution);
  visitor.Visit("disparity_noise", &disparity_noise);
  visitor.Visit("max_surface_sigma", &max_surface_sigma);
  visitor.Visit("max_allocation_sigma", &max_allocation_sigma);
  visitor.Visit("behind_band_sigmas", &behind_band_sigmas);
  visitor.Visit("front_uncertain_sigmas", &front_uncertain_sigmas);
}

void FusionOptions::Validate() const {
  const std::string section = std::string(kSection) + ".";
  if (!(voxel_size > 0) || !std::isfinite(voxel_size))
    throw std::invalid_argument(section + "voxel_size must be a finite number > 0");
  if (!(truncation >= voxel_size) || !std::isfinite(truncation))
    throw std::invalid_argument(section + "truncation must be at least one voxel");
  if (block_resolution < 2 || block_resolution > kMaxBlockResolution)
    throw std::invalid_argument(section + "block_resolution must be from 2 to " +
                                std::to_string(kMaxBlockResolution));
  if (!(disparity_noise > 0) || !std::isfinite(disparity_noise))
    throw std::invalid_argument(section + "disparity_noise must be a finite number > 0");
  if (!(max_surface_sigma > 0) || !std::isfinite(max_surface_sigma))
    throw std::invalid_argument(section + "max_surface_sigma must be a finite number > 0");
  if (!(max_allocation_sigma > 0))
    throw std::invalid_argument(section + "max_allocation_sigma must be > 0");
  if (!(behind_band_sigmas >= 0) || !std::isfinite(behind_band_sigmas))
    throw std::invalid_argument(section + "behind_band_sigmas must be a finite number >= 0");
  if (!(front_uncertain_sigmas >= 0) || !std::isfinite(front_uncertain_sigmas))
    throw std::invalid_argument(section + "front_uncertain_sigmas must be a finite number >= 0");
}

void DenseMappingOptions::Visit(io::OptionVisitor& visitor) {
  visitor.Visit("buffered_pairs", &buffered_pairs);
  visitor.Visit("moves_per_step", &moves_per_step);
}

void DenseMappingOptions::Validate() const {
  const std::string section = std::string(kSection) + ".";
  if (buffered_pairs < 1 || moves_per_step < 1)
    throw std::invalid_argument(section + "buffered_pairs and moves_per_step must be at least 1");
}

}  // namespace stereo_fabmap_slam::dense
