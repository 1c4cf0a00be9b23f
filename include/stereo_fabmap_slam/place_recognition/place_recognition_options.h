#pragma once

#include <string>

#include "stereo_fabmap_slam/features/feature_options.h"
#include "stereo_fabmap_slam/place_recognition/fab_map.h"
#include "stereo_fabmap_slam/place_recognition/vocabulary.h"

namespace stereo_fabmap_slam::place_recognition {

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
  int training_spacing = 10;  // train_fabmap: every N-th frame of a sequence

  void Validate() const;
};

// Reads config/fabmap.yaml. `odometry_features` supplies what the file's "features" section does
// not set (detector, descriptor, thresholds). Unknown keys and bad values throw io::InputError.
PlaceRecognitionOptions LoadPlaceRecognitionOptions(
    const std::string& path, const features::FeatureOptions& odometry_features);

}  // namespace stereo_fabmap_slam::place_recognition
