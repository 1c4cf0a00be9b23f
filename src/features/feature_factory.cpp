#include "stereo_fabmap_slam/features/feature_factory.h"

#include <stdexcept>

#include <opencv2/core/hal/hal.hpp>

#if __has_include(<opencv2/xfeatures2d.hpp>)
#include <opencv2/xfeatures2d.hpp>
#define STEREO_FABMAP_SLAM_HAVE_XFEATURES2D 1
#endif

#include "stereo_fabmap_slam/features/oast_detector.h"

namespace stereo_fabmap_slam::features {
namespace {

std::string JoinNames(const std::vector<std::string>& names) {
  std::string joined;
  for (const std::string& name : names) joined += (joined.empty() ? "" : ", ") + name;
  return joined;
}

}  // namespace

double DescriptorDistance(const cv::Mat& a, int i, const cv::Mat& b, int j, int norm) {
  if (norm == cv::NORM_HAMMING) {
    return cv::hal::normHamming(a.ptr<std::uint8_t>(i), b.ptr<std::uint8_t>(j), a.cols);
  }
  return cv::norm(a.row(i), b.row(j), norm);
}

std::vector<std::string> AvailableDetectors() { return {"AGAST", "FAST", "ORB", "AKAZE", "SIFT"}; }

std::vector<std::string> AvailableDescriptors() {
  std::vector<std::string> names = {"BRISK", "ORB", "AKAZE", "SIFT"};
#ifdef STEREO_FABMAP_SLAM_HAVE_XFEATURES2D
  names.insert(names.end(), {"FREAK", "BRIEF", "DAISY"});
#endif
  return names;
}

cv::Ptr<cv::FeatureDetector> CreateDetector(const FeatureOptions& options) {
  const std::string& name = options.detector;
  if (name == "AGAST") {
    // OpenCV's AGAST key points, found in under half its time (oast_detector.h).
    return OastDetector::create(options.detector_threshold, true,
                                cv::AgastFeatureDetector::OAST_9_16);
  }
  if (name == "FAST") return cv::FastFeatureDetector::create(options.detector_threshold, true);
  if (name == "ORB") return cv::ORB::create(options.max_right_features);
  if (name == "AKAZE") return cv::AKAZE::create();
  if (name == "SIFT") return cv::SIFT::create(options.max_right_features);
  throw std::invalid_argument("unknown feature detector '" + name +
                              "'; available: " + JoinNames(AvailableDetectors()));
}

DescriptorKind CreateDescriptor(const FeatureOptions& options) {
  const std::string& name = options.descriptor;
  // Distance limits: a fifth of the bits for binary descriptors (unrelated ones differ in about
  // half); for SIFT (unit vectors scaled to 512) about half the distance of unrelated ones.
  if (name == "BRISK") return {cv::BRISK::create(), cv::NORM_HAMMING, 0.2 * 512, true};
  if (name == "ORB") return {cv::ORB::create(), cv::NORM_HAMMING, 0.2 * 256};
  if (name == "AKAZE") {
    if (options.detector != "AKAZE") {
      throw std::invalid_argument("the AKAZE descriptor needs the AKAZE detector");
    }
    return {cv::AKAZE::create(), cv::NORM_HAMMING, 0.2 * 486};
  }
  if (name == "SIFT") return {cv::SIFT::create(), cv::NORM_L2, 250.0};
#ifdef STEREO_FABMAP_SLAM_HAVE_XFEATURES2D
  if (name == "FREAK") return {cv::xfeatures2d::FREAK::create(), cv::NORM_HAMMING, 0.2 * 512};
  if (name == "BRIEF") {
    return {cv::xfeatures2d::BriefDescriptorExtractor::create(32), cv::NORM_HAMMING, 0.2 * 256};
  }
  if (name == "DAISY") return {cv::xfeatures2d::DAISY::create(), cv::NORM_L2, 0.5};
#endif
  throw std::invalid_argument("unknown or unavailable feature descriptor '" + name +
                              "'; available: " + JoinNames(AvailableDescriptors()));
}

}  // namespace stereo_fabmap_slam::features
