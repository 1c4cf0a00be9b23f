#include "stereo_fabmap_slam/features/stereo_feature_extractor.h"

#include <future>

#include "stereo_fabmap_slam/features/anms.h"

namespace stereo_fabmap_slam::features {

StereoFeatureExtractor::StereoFeatureExtractor(const FeatureOptions& feature_options,
                                               const StereoMatcherOptions& stereo_options,
                                               const geometry::StereoCamera& camera)
    : options_((feature_options.Validate(), feature_options)),
      camera_(camera),
      left_detector_(feature_options, /*stereo_candidates=*/false),
      right_detector_(feature_options, /*stereo_candidates=*/true),
      descriptor_(CreateDescriptor(feature_options)),
      second_extractor_(descriptor_.shareable ? descriptor_.extractor
                                              : CreateDescriptor(feature_options).extractor),
      matcher_(stereo_options, camera, descriptor_.norm, descriptor_.max_match_distance,
               feature_options.parallel) {}

StereoFeatureExtractor::Detected StereoFeatureExtractor::Detect(const cv::Mat& left,
                                                                const cv::Mat& right) {
  Detected detected;
  if (options_.parallel && left_detector_.supports_bands()) {
    // Worker: the right image (cheap) and the lower band of the left; this thread: the upper
    // band. Same corners as one pass over each image; the future joins the worker.
    const int split = left.rows * 3 / 5;
    std::vector<cv::KeyPoint> lower;
    std::future<void> worker = std::async(std::launch::async, [&] {
      detected.right = right_detector_.DetectRows(right, 0, right.rows);
      lower = left_detector_.DetectRows(left, split, left.rows);
    });
    detected.left = left_detector_.DetectRows(left, 0, split);
    worker.get();
    detected.left.insert(detected.left.end(), lower.begin(), lower.end());
    left_detector_.Adapt(detected.left.size());
    right_detector_.Adapt(detected.right.size());
  } else if (options_.parallel) {
    std::future<std::vector<cv::KeyPoint>> right_corners =
        std::async(std::launch::async, [&] { return right_detector_.Detect(right); });
    detected.left = left_detector_.Detect(left);
    detected.right = right_corners.get();
  } else {
    detected.left = left_detector_.Detect(left);
    detected.right = right_detector_.Detect(right);
  }
  return Select(std::move(detected), left.size());
}

StereoFeatureExtractor::Detected StereoFeatureExtractor::DetectWithoutAdapting(
    const cv::Mat& left, const cv::Mat& right) const {
  Detected detected;
  detected.left = left_detector_.DetectRows(left, 0, left.rows);
  detected.right = right_detector_.DetectRows(right, 0, right.rows);
  return Select(std::move(detected), left.size());
}

StereoFeatureExtractor::Detected StereoFeatureExtractor::Select(Detected detected,
                                                                const cv::Size& size) const {
  detected.left = options_.anms ? SelectWithAnms(std::move(detected.left), options_.max_features,
                                                 size, options_.anms_tolerance)
                                : SelectStrongest(std::move(detected.left), options_.max_features);
  detected.right = SelectStrongest(std::move(detected.right), options_.max_right_features);
  return detected;
}

StereoFeatureExtractor::Described StereoFeatureExtractor::Describe(const cv::Mat& left,
                                                                   const cv::Mat& right,
                                                                   Detected detected) const {
  // compute() drops key points it cannot describe (too close to the border).
  Described described;
  described.right = std::move(detected.right);
  if (options_.parallel && !matcher_.uses_descriptors()) {
    // Two halves of the left key points on two threads; concatenated in order.
    const std::size_t half = detected.left.size() / 2;
    std::vector<cv::KeyPoint> second(detected.left.begin() + static_cast<std::ptrdiff_t>(half),
                                     detected.left.end());
    detected.left.resize(half);
    cv::Mat second_descriptors;
    std::future<void> worker = std::async(
        std::launch::async, [&] { second_extractor_->compute(left, second, second_descriptors); });
    descriptor_.extractor->compute(left, detected.left, described.left_descriptors);
    worker.get();
    described.left = std::move(detected.left);
    described.left.insert(described.left.end(), second.begin(), second.end());
    cv::vconcat(described.left_descriptors, second_descriptors, described.left_descriptors);
    return described;
  }
  described.left = std::move(detected.left);
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
