#pragma once

// A LoopDetector over a small vocabulary and Chow-Liu tree trained on random binary descriptors,
// for tests of what comes after FAB-MAP (verification, the keyframe map, map files): FAB-MAP's
// own quality is measured elsewhere. Another seed gives another vocabulary.

#include <utility>
#include <vector>

#include <opencv2/core.hpp>

#include "stereo_fabmap_slam/place_recognition/loop_detector.h"
#include "stereo_world.h"

namespace stereo_fabmap_slam::test {

inline place_recognition::LoopDetector ToyLoopDetector(
    std::uint64_t seed, const place_recognition::LoopDetectorOptions& options = {}) {
  cv::Mat training(400, 64, CV_8U);
  cv::RNG rng(seed);
  rng.fill(training, cv::RNG::UNIFORM, 0, 256);
  place_recognition::VocabularyOptions vocabulary_options;
  vocabulary_options.branching = 4;
  vocabulary_options.depth = 2;
  place_recognition::Vocabulary vocabulary =
      place_recognition::Vocabulary::Train(training, vocabulary_options);
  std::vector<std::vector<int>> word_sets;
  for (int image = 0; image < 8; ++image) {
    word_sets.push_back(vocabulary.WordSet(training.rowRange(image * 50, image * 50 + 50)));
  }
  place_recognition::FabMap fabmap(
      place_recognition::ChowLiuTree::Train(word_sets, vocabulary.size()),
      place_recognition::FabMapOptions());
  return place_recognition::LoopDetector(options, std::move(vocabulary), std::move(fabmap),
                                         kTestCamera, cv::NORM_HAMMING, 60.0);
}

}  // namespace stereo_fabmap_slam::test
