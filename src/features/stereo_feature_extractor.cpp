#include "stereo_fabmap_slam/features/stereo_feature_extractor.h"

#include <future>

#include "stereo_fabmap_slam/features/anms.h"

namespace stereo_fabmap_slam::features {

int StereoFeatures::CountWithDepth() const {
  int count = 0;
  for (std::size_t i = 0; i < size(); ++i) count += HasDepth(i) ? 1 : 0;
  return count;
}

StereoFeatureExtractor::StereoFeatureExtractor(const FeatureOptions& feature_options,
                                               const StereoMatcherOptions& stereo_options,
                                               const camera::StereoCamera& camera)
    : options_((feature_options.Validate(), feature_options)),
      camera_(camera),
      left_detector_(feature_options),
      right_detector_(feature_options),
      descriptor_(CreateDescriptor(feature_options)),
      matcher_(stereo_options, camera, descriptor_.norm, descriptor_.max_match_distance) {}

StereoFeatureExtractor::Detected StereoFeatureExtractor::Detect(const cv::Mat& left,
                                                                const cv::Mat& right) {
  Detected detected;
  if (options_.parallel) {
    // The two streams share nothing; the future joins the worker before we return.
    std::future<std::vector<cv::KeyPoint>> right_corners =
        std::async(std::launch::async, [&] { return right_detector_.Detect(right); });
    detected.left = left_detector_.Detect(left);
    detected.right = right_corners.get();
  } else {
    detected.left = left_detector_.Detect(left);
    detected.right = right_detector_.Detect(right);
  }
  detected.left = options_.anms ? SelectWithAnms(std::move(detected.left), options_.max_features,
                                                 left.size(), options_.anms_tolerance)
                                : SelectStrongest(std::move(detected.left), options_.max_features);
  detected.right = SelectStrongest(std::move(detected.right), options_.max_right_features);
  return detected;
}

StereoFeatureExtractor::Described StereoFeatureExtractor::Describe(const cv::Mat& left,
                                                                   const cv::Mat& right,
                                                                   Detected detected) const {
  // compute() drops key points it cannot describe (too close to the border).
  Described described;
  described.left = std::move(detected.left);
  described.right = std::move(detected.right);
  descriptor_.extractor->compute(left, described.left, described.left_descriptors);
  if (matcher_.uses_descriptors()) {
    descriptor_.extractor->compute(right, described.right, described.right_descriptors);
  }
  return described;
}

StereoFeatures StereoFeatureExtractor::Match(const cv::Mat& left, const cv::Mat& right,
                                             Described described) const {
  StereoFeatures features;
  features.keypoints = std::move(described.left);
  features.descriptors = described.left_descriptors;
  features.u_right = matcher_.Match(left, features.keypoints, features.descriptors, right,
                                    described.right, described.right_descriptors);
  features.points.resize(features.size(), Eigen::Vector3d::Zero());
  for (std::size_t i = 0; i < features.size(); ++i) {
    if (!features.HasDepth(i)) continue;
    const cv::Point2f& p = features.keypoints[i].pt;
    features.points[i] = camera_.Triangulate(p.x, p.y, p.x - features.u_right[i]);
  }
  return features;
}

StereoFeatures StereoFeatureExtractor::Extract(const cv::Mat& left, const cv::Mat& right) {
  return Match(left, right, Describe(left, right, Detect(left, right)));
}

}  // namespace stereo_fabmap_slam::features
