#include "stereo_fabmap_slam/features/adaptive_detector.h"

#include <algorithm>
#include <cmath>

#include "stereo_fabmap_slam/features/feature_factory.h"

namespace stereo_fabmap_slam::features {

AdaptiveDetector::AdaptiveDetector(const FeatureOptions& options)
    : options_(options),
      detector_(CreateDetector(options)),
      adaptive_(options.adaptive_threshold &&
                (options.detector == "AGAST" || options.detector == "FAST")),
      threshold_(options.detector_threshold) {}

std::vector<cv::KeyPoint> AdaptiveDetector::Detect(const cv::Mat& image) {
  std::vector<cv::KeyPoint> keypoints;
  detector_->detect(image, keypoints);
  if (!adaptive_) return keypoints;
  // Corner counts fall roughly exponentially with the threshold: steps of 10 % are gentle enough
  // not to oscillate and quick enough to follow a change of scene within a few frames.
  const double count = static_cast<double>(keypoints.size());
  const double target_low = 2.0 * options_.max_features, target_high = 4.0 * options_.max_features;
  int next = threshold_;
  if (count < target_low) next = static_cast<int>(std::floor(threshold_ * 0.9));
  if (count > target_high) next = static_cast<int>(std::ceil(threshold_ * 1.1));
  next = std::clamp(next, options_.min_detector_threshold, options_.max_detector_threshold);
  if (next != threshold_) {
    threshold_ = next;
    if (auto agast = detector_.dynamicCast<cv::AgastFeatureDetector>()) agast->setThreshold(next);
    if (auto fast = detector_.dynamicCast<cv::FastFeatureDetector>()) fast->setThreshold(next);
  }
  return keypoints;
}

}  // namespace stereo_fabmap_slam::features
