#pragma once

#include <vector>

#include <opencv2/features2d.hpp>

#include "stereo_fabmap_slam/concurrency/helper_thread.h"
#include "stereo_fabmap_slam/features/adaptive_detector.h"
#include "stereo_fabmap_slam/features/feature_factory.h"
#include "stereo_fabmap_slam/features/features_options.h"
#include "stereo_fabmap_slam/features/stereo_features.h"
#include "stereo_fabmap_slam/features/stereo_matcher.h"
#include "stereo_fabmap_slam/geometry/stereo_camera.h"

namespace stereo_fabmap_slam::features {

// From a rectified stereo pair to StereoFeatures, in three stages that callers may time apart:
// detection (+ ANMS on the left, strongest on the right), description (left; right only for
// descriptor stereo matching), stereo matching and triangulation. Detection adapts its threshold
// per stream, so one extractor serves one camera pair in time order.
class StereoFeatureExtractor {
 public:
  struct Detected {
    std::vector<cv::KeyPoint> left, right;
  };
  struct Described {
    std::vector<cv::KeyPoint> left, right;
    cv::Mat left_descriptors, right_descriptors;
  };

  // Throws std::invalid_argument for bad options or an unknown detector/descriptor. helper:
  // shares each stage's work with the calling thread if feature_options.parallel (null: the
  // calling thread alone; the results are the same either way).
  StereoFeatureExtractor(const FeatureOptions& feature_options,
                         const StereoMatcherOptions& stereo_options,
                         const geometry::StereoCamera& camera,
                         concurrency::HelperThread* helper = nullptr);

  Detected Detect(const cv::Mat& left, const cv::Mat& right);
  // The same corners for a pair outside the stream (e.g. a view checked against the map): the
  // thresholds stay as they are, so the stream's detection is not disturbed. One thread.
  Detected DetectWithoutAdapting(const cv::Mat& left, const cv::Mat& right) const;
  Described Describe(const cv::Mat& left, const cv::Mat& right, Detected detected) const;
  StereoFeatures Match(const cv::Mat& left, const cv::Mat& right, Described described) const;
  StereoFeatures Extract(const cv::Mat& left, const cv::Mat& right);

  const DescriptorKind& descriptor() const { return descriptor_; }
  int descriptor_norm() const { return descriptor_.norm; }
  double max_match_distance() const { return descriptor_.max_match_distance; }
  const geometry::StereoCamera& camera() const { return camera_; }

 private:
  // The raw corners of both images, split into pieces for the helper if there is one.
  Detected DetectCorners(const cv::Mat& left, const cv::Mat& right,
                         concurrency::HelperThread* helper) const;
  Detected Select(Detected detected, const cv::Size& size) const;  // ANMS or strongest

  FeatureOptions options_;
  geometry::StereoCamera camera_;
  AdaptiveDetector left_detector_, right_detector_;
  DescriptorKind descriptor_;
  // For the second thread: the same one if it is shareable, else its own.
  cv::Ptr<cv::DescriptorExtractor> second_extractor_;
  StereoMatcher matcher_;
  concurrency::HelperThread* helper_;  // not owned; may be null
};

}  // namespace stereo_fabmap_slam::features
