#pragma once

#include <string>
#include <vector>

#include <opencv2/features2d.hpp>

#include "stereo_fabmap_slam/features/features_options.h"

namespace stereo_fabmap_slam::features {

// Names this build of OpenCV provides (FREAK, BRIEF and DAISY need opencv_xfeatures2d, which
// Debian's OpenCV does not ship).
std::vector<std::string> AvailableDetectors();
std::vector<std::string> AvailableDescriptors();

// A descriptor extractor with how its descriptors compare.
struct DescriptorKind {
  cv::Ptr<cv::DescriptorExtractor> extractor;
  int norm = cv::NORM_HAMMING;    // NORM_HAMMING for binary descriptors, NORM_L2 for float ones
  double max_match_distance = 0;  // beyond this two descriptors are never the same point
  // Its compute() keeps no state between calls, so one instance may serve several threads and
  // users: checked for BRISK in OpenCV 4.6 (computeDescriptorsAndOrOrientation is const and
  // works on local buffers), whose instance holds a 47 MB pattern table (64 scales x 1,024
  // rotations x 60 points). Not claimed for the others.
  bool shareable = false;
};

// Distance between row `i` of `a` and row `j` of `b` under `norm` (Hamming on raw bytes for
// binary descriptors: far cheaper than cv::norm on Mat rows in the inner matching loops).
double DescriptorDistance(const cv::Mat& a, int i, const cv::Mat& b, int j, int norm);

// Throw std::invalid_argument with the list of available names for an unknown or unavailable one.
cv::Ptr<cv::FeatureDetector> CreateDetector(const FeatureOptions& options);
DescriptorKind CreateDescriptor(const FeatureOptions& options);

}  // namespace stereo_fabmap_slam::features
