#pragma once

#include <vector>

#include <opencv2/core.hpp>

#include "stereo_fabmap_slam/features/adaptive_detector.h"
#include "stereo_fabmap_slam/features/feature_factory.h"
#include "stereo_fabmap_slam/features/features_options.h"

namespace stereo_fabmap_slam::place_recognition {

// Key points and descriptors of one image with the odometry's detector, ANMS and descriptor, so
// that place recognition sees the features the keyframes carry.
class ImageDescriber {
 public:
  explicit ImageDescriber(const features::FeatureOptions& options);
  // The same with a descriptor instance made for `options.descriptor` elsewhere (shareable: a
  // BRISK's 47 MB table once per process, not once per user).
  ImageDescriber(const features::FeatureOptions& options, features::DescriptorKind descriptor);
  // Descriptors of a mono8 image, one per row (CV_8U binary or CV_32F).
  cv::Mat Describe(const cv::Mat& image);
  // The same for an image outside the stream: the detector's threshold does not adapt.
  cv::Mat DescribeWithoutAdapting(const cv::Mat& image) const;

 private:
  cv::Mat Compute(const cv::Mat& image, std::vector<cv::KeyPoint> keypoints) const;

  features::FeatureOptions options_;
  features::AdaptiveDetector detector_;
  features::DescriptorKind descriptor_;
};

}  // namespace stereo_fabmap_slam::place_recognition
