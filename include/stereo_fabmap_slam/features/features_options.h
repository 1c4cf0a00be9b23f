#pragma once

#include <ostream>
#include <string>

#include "stereo_fabmap_slam/io/option_reader.h"

namespace stereo_fabmap_slam::features {

struct FeatureOptions {
  static constexpr char kSection[] = "features";

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
  bool parallel = true;         // share each stage with the front end's second thread
  bool anms = true;             // spread key points with adaptive non-maximal suppression
  double anms_tolerance = 0.1;  // ANMS may return max_features within this fraction

  void Visit(io::OptionVisitor& visitor);
  void Validate() const;  // throws std::invalid_argument naming the bad value
};

// How the right image's candidates are compared with a left key point.
enum class StereoMatchMode { kPatch, kDescriptor };

struct StereoMatcherOptions {
  static constexpr char kSection[] = "stereo";

  // "patch": right candidates are compared with the left key point by zero-mean normalised
  // cross-correlation of image patches, so the right image needs no descriptors (fast);
  // "descriptor": by descriptor distance (the right key points are described too).
  StereoMatchMode mode = StereoMatchMode::kPatch;
  double max_patch_distance = 0.3;  // patch mode: 1 - NCC of a match must stay below this
  double max_row_difference = 2.0;  // [px] rectified rows of a match may differ this much
  double max_disparity = 150.0;     // [px] closest points (~0.3 m on EuRoC)
  double ratio = 0.8;               // best distance / second best must stay below this
  double min_depth = 0.2;           // [m]
  double max_depth = 25.0;          // [m] farther points triangulate too poorly to keep
  bool subpixel = true;             // refine the right column by patch correlation
  int patch_radius = 5;             // [px] half side of the correlation patch
  int search_radius = 3;            // [px] columns searched either side of the matched key point

  void Visit(io::OptionVisitor& visitor);
  void Validate() const;
};

}  // namespace stereo_fabmap_slam::features
