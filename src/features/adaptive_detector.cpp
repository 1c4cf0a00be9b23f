#include "stereo_fabmap_slam/features/adaptive_detector.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "stereo_fabmap_slam/features/feature_factory.h"

namespace stereo_fabmap_slam::features {
namespace {

// Rows beyond a band that the segment test (circle of radius 3) and the 3x3 non-maximum
// suppression need to decide every corner inside the band as on the whole image.
constexpr int kBandMargin = 4;

}  // namespace

AdaptiveDetector::AdaptiveDetector(const FeatureOptions& options, bool stereo_candidates)
    : options_(options),
      segment_test_(options.detector == "AGAST" || options.detector == "FAST"),
      adaptive_(options.adaptive_threshold && segment_test_),
      threshold_(options.detector_threshold) {
  if (stereo_candidates && options.detector == "AGAST") {
    FeatureOptions fast = options;
    fast.detector = "FAST";
    detector_ = CreateDetector(fast);
  } else {
    detector_ = CreateDetector(options);
  }
}

std::vector<cv::KeyPoint> AdaptiveDetector::Detect(const cv::Mat& image) {
  std::vector<cv::KeyPoint> keypoints = DetectRows(image, 0, image.rows);
  Adapt(keypoints.size());
  return keypoints;
}

std::vector<cv::KeyPoint> AdaptiveDetector::DetectRows(const cv::Mat& image, int row_begin,
                                                       int row_end) const {
  std::vector<cv::KeyPoint> keypoints;
  if (row_begin == 0 && row_end == image.rows) {
    detector_->detect(image, keypoints);
    return keypoints;
  }
  if (!segment_test_) throw std::logic_error("band detection needs AGAST or FAST");
  const int top = std::max(0, row_begin - kBandMargin);
  const int bottom = std::min(image.rows, row_end + kBandMargin);
  detector_->detect(image.rowRange(top, bottom), keypoints);
  std::vector<cv::KeyPoint> inside;
  inside.reserve(keypoints.size());
  for (cv::KeyPoint& k : keypoints) {
    k.pt.y += static_cast<float>(top);
    if (k.pt.y >= row_begin && k.pt.y < row_end) inside.push_back(k);
  }
  return inside;
}

void AdaptiveDetector::Adapt(std::size_t corner_count) {
  if (!adaptive_) return;
  // Corner counts fall roughly exponentially with the threshold: steps of 10 % are gentle enough
  // not to oscillate and quick enough to follow a change of scene within a few frames.
  const double count = static_cast<double>(corner_count);
  const double target_low = 1.5 * options_.max_features, target_high = 3.0 * options_.max_features;
  int next = threshold_;
  if (count < target_low) next = static_cast<int>(std::floor(threshold_ * 0.9));
  if (count > target_high) next = static_cast<int>(std::ceil(threshold_ * 1.1));
  next = std::clamp(next, options_.min_detector_threshold, options_.max_detector_threshold);
  if (next == threshold_) return;
  threshold_ = next;
  if (auto agast = detector_.dynamicCast<cv::AgastFeatureDetector>()) agast->setThreshold(next);
  if (auto fast = detector_.dynamicCast<cv::FastFeatureDetector>()) fast->setThreshold(next);
}

}  // namespace stereo_fabmap_slam::features
