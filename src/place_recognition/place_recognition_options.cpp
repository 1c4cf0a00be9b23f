#include "stereo_fabmap_slam/place_recognition/place_recognition_options.h"

#include <cmath>
#include <limits>
#include <stdexcept>

#include "stereo_fabmap_slam/io/input_error.h"
#include "stereo_fabmap_slam/io/options_file.h"

namespace stereo_fabmap_slam::place_recognition {

void VocabularyOptions::Visit(io::OptionVisitor& visitor) {
  visitor.Visit("branching", &branching);
  visitor.Visit("depth", &depth);
  visitor.Visit("iterations", &iterations);
  visitor.Visit("seed", &seed);
}

void VocabularyOptions::Validate() const {
  if (branching < 2 || depth < 1 || iterations < 1) {
    throw std::invalid_argument("vocabulary: branching >= 2, depth >= 1, iterations >= 1");
  }
  double words = 1;
  for (int i = 0; i < depth; ++i) words *= branching;
  if (words > 1e7)
    throw std::invalid_argument("vocabulary: branching^depth must not exceed 10^7 words");
}

void FabMapOptions::Visit(io::OptionVisitor& visitor) {
  static constexpr io::EnumName<DetectorModelSource> kDetectorModels[] = {
      {DetectorModelSource::kTrained, "trained"}, {DetectorModelSource::kFixed, "fixed"}};
  io::VisitEnum(visitor, "detector_model", &detector_model, kDetectorModels);
  visitor.Visit("p_z_given_e", &p_z_given_e);
  visitor.Visit("p_z_given_not_e", &p_z_given_not_e);
  visitor.Visit("new_place_prior", &new_place_prior);
  visitor.Visit("smoothing", &smoothing);
  static constexpr io::EnumName<NewPlaceModel> kNewPlaceModels[] = {
      {NewPlaceModel::kMeanField, "mean_field"}, {NewPlaceModel::kSampling, "sampling"}};
  static constexpr io::EnumName<LocationPrior> kLocationPriors[] = {
      {LocationPrior::kUniform, "uniform"}, {LocationPrior::kMotion, "motion"}};
  io::VisitEnum(visitor, "new_place_model", &new_place_model, kNewPlaceModels);
  io::VisitEnum(visitor, "location_prior", &location_prior, kLocationPriors);
  visitor.Visit("motion_weight", &motion_weight);
  visitor.Visit("inverted_index", &inverted_index);
  visitor.Visit("exact_tree_corrections", &exact_tree_corrections);
  visitor.Visit("match_log_odds", &match_log_odds);
  visitor.Visit("update_near_first_view", &update_near_first_view);
  visitor.Visit("max_place_extent", &max_place_extent);
  visitor.Visit("max_place_turn_deg", &max_place_turn_deg);
}

void ValidateDetectorRates(double p_z_given_e, double p_z_given_not_e, const std::string& what) {
  if (!(p_z_given_e > 0 && p_z_given_e < 1) ||
      !(p_z_given_not_e >= 0 && p_z_given_not_e < p_z_given_e)) {
    throw std::invalid_argument(what + ": need 0 <= p_z_given_not_e < p_z_given_e < 1");
  }
}

void FabMapOptions::Validate() const {
  ValidateDetectorRates(p_z_given_e, p_z_given_not_e, "fabmap");
  if (!(new_place_prior > 0 && new_place_prior < 1))
    throw std::invalid_argument("fabmap.new_place_prior must lie in (0, 1)");
  if (!(smoothing > 0 && smoothing <= 1))
    throw std::invalid_argument("fabmap.smoothing must lie in (0, 1]");
  if (!(motion_weight >= 0 && motion_weight <= 1))
    throw std::invalid_argument("fabmap.motion_weight must lie in [0, 1]");
  if (!std::isfinite(match_log_odds))
    throw std::invalid_argument("fabmap.match_log_odds must be a finite number");
  if (!(max_place_extent > 0))
    throw std::invalid_argument("fabmap.max_place_extent must be > 0 (.inf: no limit)");
  if (!(max_place_turn_deg > 0 && max_place_turn_deg <= 180))
    throw std::invalid_argument("fabmap.max_place_turn_deg must lie in (0, 180]");
}

void LoopDetectorOptions::Visit(io::OptionVisitor& visitor) {
  visitor.Visit("min_age", &min_age);
  visitor.Visit("min_probability", &min_probability);
  visitor.Visit("min_log_odds", &min_log_odds);
  visitor.Visit("max_candidates", &max_candidates);
  visitor.Visit("sequence_length", &sequence_length);
  visitor.Visit("sequence_max_step", &sequence_max_step);
  visitor.Visit("match_ratio", &match_ratio);
  io::VisitEnum(visitor, "pnp_kernel", &pnp_kernel, geometry::kPnpKernelNames);
  visitor.Visit("ransac_threshold", &ransac_threshold);
  visitor.Visit("ransac_iterations", &ransac_iterations);
  visitor.Visit("min_inliers", &min_inliers);
  visitor.Visit("min_inlier_cells", &min_inlier_cells);
  visitor.Visit("max_drift_fraction", &max_drift_fraction);
  visitor.Visit("min_drift_allowance", &min_drift_allowance);
  visitor.Visit("max_rotation_drift_deg", &max_rotation_drift_deg);
  visitor.Visit("loop_consistency_path", &loop_consistency_path);
  visitor.Visit("max_loop_distance", &max_loop_distance);
  visitor.Visit("translation_sigma", &translation_sigma);
  visitor.Visit("rotation_sigma_deg", &rotation_sigma_deg);
}

void LoopDetectorOptions::Validate() const {
  if (!(min_age >= 0)) throw std::invalid_argument("loop_detection.min_age must be >= 0");
  if (!(min_probability >= 0 && min_probability <= 1)) {
    throw std::invalid_argument("loop_detection.min_probability must lie in [0, 1]");
  }
  if (std::isnan(min_log_odds) || min_log_odds == std::numeric_limits<double>::infinity())
    throw std::invalid_argument(
        "loop_detection.min_log_odds must be a number (or -.inf: no floor)");
  if (max_candidates < 1) throw std::invalid_argument("loop_detection.max_candidates must be >= 1");
  if (sequence_length < 1 || sequence_max_step < 0) {
    throw std::invalid_argument(
        "loop_detection.sequence_length must be >= 1 and sequence_max_step >= 0");
  }
  if (!(match_ratio > 0 && match_ratio <= 1)) {
    throw std::invalid_argument("loop_detection.match_ratio must lie in (0, 1]");
  }
  if (!(ransac_threshold > 0) || ransac_iterations < 1) {
    throw std::invalid_argument("loop_detection RANSAC threshold and iterations must be > 0");
  }
  if (min_inliers < 6) throw std::invalid_argument("loop_detection.min_inliers must be >= 6");
  if (min_inlier_cells < 1 || min_inlier_cells > 16) {
    throw std::invalid_argument("loop_detection.min_inlier_cells must lie in [1, 16]");
  }
  if (!(max_drift_fraction > 0) || !(min_drift_allowance > 0) || !(max_rotation_drift_deg > 0)) {
    throw std::invalid_argument("loop_detection drift allowances must be > 0");
  }
  if (!(loop_consistency_path >= 0)) {
    throw std::invalid_argument("loop_detection.loop_consistency_path must be >= 0 (0: off)");
  }
  if (!(max_loop_distance > 0)) {
    throw std::invalid_argument("loop_detection.max_loop_distance must be > 0");
  }
  if (!(translation_sigma > 0) || !(rotation_sigma_deg > 0)) {
    throw std::invalid_argument("loop_detection sigmas must be > 0");
  }
}

void TrainingOptions::Validate() const {
  if (spacing < 1) throw std::invalid_argument("training.spacing must be >= 1");
}

void PlaceRecognitionOptions::Validate() const {
  features.Validate();
  vocabulary.Validate();
  fabmap.Validate();
  training.Validate();
}

PlaceRecognitionOptions LoadPlaceRecognitionOptions(
    const std::string& path, const features::FeatureOptions& odometry_features) {
  const io::OptionsFile file = io::OptionsFile::Load(path);
  file.RejectUnknownSections({"vocabulary_directory", features::FeatureOptions::kSection,
                              VocabularyOptions::kSection, FabMapOptions::kSection,
                              TrainingOptions::kSection});
  PlaceRecognitionOptions options;
  options.features = file.Read(odometry_features);
  options.vocabulary = file.Read<VocabularyOptions>();
  options.fabmap = file.Read<FabMapOptions>();
  options.training = file.Read<TrainingOptions>();
  options.vocabulary_directory = file.Path("vocabulary_directory").value_or("");
  return options;
}

}  // namespace stereo_fabmap_slam::place_recognition
