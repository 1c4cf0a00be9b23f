#pragma once

#include <string>

#include "stereo_fabmap_slam/place_recognition/chow_liu_tree.h"
#include "stereo_fabmap_slam/place_recognition/place_database.h"
#include "stereo_fabmap_slam/place_recognition/vocabulary.h"

namespace stereo_fabmap_slam::tools {

// What train_fabmap writes into one folder: the vocabulary, the Chow-Liu tree over its words
// and the training places (the sampled new-place model, tf-idf's document frequencies); the
// detector model beside them is read by place_recognition::ResolveDetectorModel.
struct FabMapFiles {
  std::string directory;  // for place_recognition::ResolveDetectorModel
  place_recognition::Vocabulary vocabulary;
  place_recognition::ChowLiuTree tree;
  place_recognition::PlaceDatabase training_places;
};

// Loads the three from the folder of `vocabulary_file` (a --vocabulary argument: vocabulary.bin
// with chow_liu_tree.bin and training_places.bin beside it). Throws what the loaders throw, or
// std::runtime_error for a path without a folder.
FabMapFiles LoadFabMapFiles(const std::string& vocabulary_file);

}  // namespace stereo_fabmap_slam::tools
