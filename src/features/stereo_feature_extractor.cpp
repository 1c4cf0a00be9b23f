#include "stereo_fabmap_slam/features/stereo_feature_extractor.h"

#include "stereo_fabmap_slam/features/anms.h"

namespace stereo_fabmap_slam::features {

StereoFeatureExtractor::StereoFeatureExtractor(const FeatureOptions& feature_options,
                                               const StereoMatcherOptions& stereo_options,
                                               const geometry::StereoCamera& camera,
                                               concurrency::HelperThread* helper)
    : options_((feature_options.Validate(), feature_options)),
      camera_(camera),
      left_detector_(feature_options, /*stereo_candidates=*/false),
      right_detector_(feature_options, /*stereo_candidates=*/true),
      descriptor_(CreateDescriptor(feature_options)),
      second_extractor_(descriptor_.shareable ? descriptor_.extractor
                                              : CreateDescriptor(feature_options).extractor),
      matcher_(stereo_options, camera, descriptor_.norm, descriptor_.max_match_distance,
               feature_options.parallel ? helper : nullptr),
      helper_(feature_options.parallel ? helper : nullptr) {}

StereoFeatureExtractor::Detected StereoFeatureExtractor::Detect(const cv::Mat& left,
                                                                const cv::Mat& right) {
  Detected detected = DetectCorners(left, right, helper_);
  left_detector_.Adapt(detected.left.size());
  right_detector_.Adapt(detected.right.size());
  return Select(std::move(detected), left.size());
}

StereoFeatureExtractor::Detected StereoFeatureExtractor::DetectWithoutAdapting(
    const cv::Mat& left, const cv::Mat& right) const {
  return Select(DetectCorners(left, right, nullptr), left.size());
}

StereoFeatureExtractor::Detected StereoFeatureExtractor::DetectCorners(
    const cv::Mat& left, const cv::Mat& right, concurrency::HelperThread* helper) const {
  // Three pieces: the upper and lower bands of the left image and the whole right one (FAST
  // for stereo candidates, a fifth of AGAST's time), about equal halves for two threads
  // whichever takes which. The split is the same with or without a helper, so the corners do
  // not depend on the threads. They are those of one pass over the left image except where
  // AGAST's suppression, which keeps one corner of each 4-connected blob of corners, meets a
  // blob the split cuts (features_test: BandDetectionDiffersFromTheWholeImageOnlyAtTheSplit);
  // a detector without bands takes the whole image.
  const bool bands = left_detector_.supports_bands();
  const int split = bands ? left.rows * 3 / 5 : left.rows;
  Detected detected;
  std::vector<cv::KeyPoint> lower;
  const auto detect = [&](int piece) {
    if (piece == 0) detected.left = left_detector_.DetectRows(left, 0, split);
    if (piece == 1) detected.right = right_detector_.DetectRows(right, 0, right.rows);
    if (piece == 2) lower = left_detector_.DetectRows(left, split, left.rows);
  };
  const int pieces = bands ? 3 : 2;
  if (helper != nullptr) {
    helper->ForEachPiece(pieces, detect);
  } else {
    for (int piece = 0; piece < pieces; ++piece) detect(piece);
  }
  detected.left.insert(detected.left.end(), lower.begin(), lower.end());
  return detected;
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
  if (helper_ != nullptr && !matcher_.uses_descriptors()) {
    // Two halves of the left key points on two threads, concatenated in order: a shareable
    // extractor (BRISK) serves both, one that is not has a second instance. Not more pieces:
    // BRISK integrates the whole image on every call (0.04 ms), and its time per key point
    // varies little, so halves balance the threads.
    const std::size_t half = detected.left.size() / 2;
    std::vector<cv::KeyPoint> second(detected.left.begin() + static_cast<std::ptrdiff_t>(half),
                                     detected.left.end());
    described.left = std::move(detected.left);
    described.left.resize(half);
    cv::Mat second_descriptors;
    helper_->ForEachPiece(2, [&](int piece) {
      if (piece == 0) {
        descriptor_.extractor->compute(left, described.left, described.left_descriptors);
      } else {
        second_extractor_->compute(left, second, second_descriptors);
      }
    });
    described.left.insert(described.left.end(), second.begin(), second.end());
    if (described.left_descriptors.empty()) {
      described.left_descriptors = second_descriptors;
    } else if (!second_descriptors.empty()) {
      cv::vconcat(described.left_descriptors, second_descriptors, described.left_descriptors);
    }
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
