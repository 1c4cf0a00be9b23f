#pragma once

#include <vector>

#include <opencv2/features2d.hpp>

#include "stereo_fabmap_slam/features/feature_options.h"

namespace stereo_fabmap_slam::features {

// A detector for one camera stream. For AGAST and FAST with adaptive_threshold, the threshold
// follows the scene: after each image it moves towards a raw corner count of 2 to 4 times
// max_features, so that the next, similar image costs a bounded detection time.
class AdaptiveDetector {
 public:
  explicit AdaptiveDetector(const FeatureOptions& options);

  std::vector<cv::KeyPoint> Detect(const cv::Mat& image);
  int threshold() const { return threshold_; }

 private:
  FeatureOptions options_;
  cv::Ptr<cv::FeatureDetector> detector_;
  bool adaptive_ = false;
  int threshold_ = 0;
};

}  // namespace stereo_fabmap_slam::features
