#pragma once

#include <string>

#include "stereo_fabmap_slam/features/features_options.h"
#include "stereo_fabmap_slam/io/option_reader.h"

namespace stereo_fabmap_slam::place_recognition {

struct VocabularyOptions {
  static constexpr char kSection[] = "vocabulary";

  int branching = 10;  // children per node
  int depth = 4;       // levels: up to branching^depth words (10,000 by default)
  int iterations = 8;  // clustering iterations per node
  int seed = 1;

  void Visit(io::OptionVisitor& visitor);
  void Validate() const;  // throws std::invalid_argument
};

// p(Z | new place): the mean-field approximation, or an average over sampled training places.
enum class NewPlaceModel { kMeanField, kSampling };
// The prior over places: uniform, or favouring the neighbours of the last match.
enum class LocationPrior { kUniform, kMotion };

struct FabMapOptions {
  static constexpr char kSection[] = "fabmap";

  double p_z_given_e = 0.39;     // detector model: p(word seen | scene element present)
  double p_z_given_not_e = 0.0;  // p(word seen | element absent): false detections
  double new_place_prior = 0.9;  // prior that a view shows a place not in the map
  double smoothing = 0.99;       // posterior smoothing: p -> s p + (1 - s) / (places + 1)
  NewPlaceModel new_place_model = NewPlaceModel::kMeanField;  // mean_field, or sampling
  LocationPrior location_prior = LocationPrior::kUniform;     // uniform, or motion
  double motion_weight = 0.6;  // motion prior: share of the existing-place mass on neighbours
  bool inverted_index = true;  // FAB-MAP 2.0 (inverted index); false: FAB-MAP 1.0 (every word)
  // FAB-MAP 2.0 only. false: a word absent from the view is scored as if its Chow-Liu parent
  // were absent too, so that only the view's own words are looked up (half the index reads;
  // it finds the same best place as FAB-MAP 1.0, see the tests). true: also correct the absent
  // children of the view's words, giving FAB-MAP 1.0's log-likelihoods (to the single precision
  // in which 2.0 sums each place's corrections: within 1e-6 of the value) and ranking.
  bool exact_tree_corrections = false;
  double match_threshold = 0.5;  // Add(): update the best place at this posterior, else add one

  void Visit(io::OptionVisitor& visitor);
  void Validate() const;  // throws std::invalid_argument
};

struct TrainingOptions {
  static constexpr char kSection[] = "training";

  int spacing = 10;  // train_fabmap: every N-th frame of a sequence, so that views are distinct

  void Visit(io::OptionVisitor& visitor) { visitor.Visit("spacing", &spacing); }
  void Validate() const;  // throws std::invalid_argument
};

// Everything place recognition is configured with (config/fabmap.yaml).
struct PlaceRecognitionOptions {
  // Folder with vocabulary.bin, chow_liu_tree.bin and training_places.bin (train_fabmap); a
  // relative path is relative to the configuration file.
  std::string vocabulary_directory;
  // The odometry's detector and descriptor, with a selection of its own: place recognition
  // wants the strongest corners (they recur from view to view), odometry wants them spread out.
  features::FeatureOptions features;
  VocabularyOptions vocabulary;
  FabMapOptions fabmap;
  TrainingOptions training;

  void Validate() const;
};

// Reads config/fabmap.yaml. `odometry_features` supplies what the file's "features" section does
// not set (detector, descriptor, thresholds). Unknown keys and bad values throw io::InputError.
PlaceRecognitionOptions LoadPlaceRecognitionOptions(
    const std::string& path, const features::FeatureOptions& odometry_features);

}  // namespace stereo_fabmap_slam::place_recognition
