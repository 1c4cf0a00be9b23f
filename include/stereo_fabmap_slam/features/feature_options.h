#pragma once

#include <ostream>
#include <string>

#include "stereo_fabmap_slam/io/option_reader.h"

namespace stereo_fabmap_slam::features {

struct FeatureOptions {
  std::string detector = "AGAST";  // AGAST, FAST, ORB, AKAZE, SIFT
  std::string descriptor =
      "BRISK";             // BRISK, ORB, AKAZE, SIFT (+ FREAK, BRIEF, DAISY with xfeatures2d)
  int max_features = 600;  // key points kept in the left image (ANMS)
  int max_right_features = 1500;  // stereo candidates kept in the right image (strongest first)
  int detector_threshold = 20;    // AGAST / FAST intensity threshold (the start value if adaptive)
  // AGAST / FAST: after each image, move the threshold (within [min, max]) so that the next one
  // yields between 1.5 and 3 times max_features raw corners. This keeps detection time and the
  // number of candidates steady from bland walls to cluttered rooms.
  bool adaptive_threshold = true;
  int min_detector_threshold = 5;
  int max_detector_threshold = 80;
  bool parallel = true;         // detect the left and right images on two threads
  bool anms = true;             // spread key points with adaptive non-maximal suppression
  double anms_tolerance = 0.1;  // ANMS may return max_features within this fraction

  void Visit(io::OptionVisitor& visitor);
  void Validate() const;  // throws std::invalid_argument naming the bad value
};

}  // namespace stereo_fabmap_slam::features
