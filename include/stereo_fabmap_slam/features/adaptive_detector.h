#pragma once

#include <cstddef>
#include <vector>

#include <opencv2/features2d.hpp>

#include "stereo_fabmap_slam/features/features_options.h"

namespace stereo_fabmap_slam::features {

// A corner detector for one camera stream.
// - For AGAST and FAST with adaptive_threshold, the threshold follows the scene: after each
//   image it moves towards a raw corner count of 1.5 to 3 times max_features, so that the next,
//   similar image costs a bounded detection time.
// - For AGAST and FAST, detection can run on bands of rows (on different threads) with the same
//   result as on the whole image.
// - As a source of stereo candidates (right image), AGAST is replaced by OpenCV's FAST: the same
//   9-of-16 segment test (identical raw corners), five times faster in OpenCV 4.6.
class AdaptiveDetector {
 public:
  AdaptiveDetector(const FeatureOptions& options, bool stereo_candidates);

  // Whole image, then adapts the threshold.
  std::vector<cv::KeyPoint> Detect(const cv::Mat& image);
  // Corners with rows in [row_begin, row_end); no adaptation. Needs supports_bands() unless the
  // band is the whole image.
  std::vector<cv::KeyPoint> DetectRows(const cv::Mat& image, int row_begin, int row_end) const;
  // Adapts the threshold to the raw corner count of the last whole image.
  void Adapt(std::size_t corner_count);

  bool supports_bands() const { return segment_test_; }

 private:
  FeatureOptions options_;
  cv::Ptr<cv::FeatureDetector> detector_;
  bool segment_test_ = false;  // AGAST or FAST
  bool adaptive_ = false;
  int threshold_ = 0;
};

}  // namespace stereo_fabmap_slam::features
