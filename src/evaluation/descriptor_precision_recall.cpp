#include "stereo_fabmap_slam/evaluation/descriptor_precision_recall.h"

#include <algorithm>
#include <limits>
#include <stdexcept>
#include <string>

#include "stereo_fabmap_slam/features/feature_factory.h"

namespace stereo_fabmap_slam::evaluation {
namespace {

// A reference key point the geometry carries: its nearest and second-nearest test descriptor
// distances, and whether the nearest is at the right place.
struct CarriedMatch {
  double d1 = 0, d2 = std::numeric_limits<double>::infinity();
  bool correct = false;
};

bool IsWithin(const cv::Point2f& a, const cv::Point2f& b, double epsilon) {
  const double dx = a.x - b.x, dy = a.y - b.y;
  return dx * dx + dy * dy <= epsilon * epsilon;
}

}  // namespace

void DescriptorPrecisionRecallOptions::Validate() const {
  if (!(epsilon > 0)) throw std::invalid_argument("epsilon must be > 0 px");
  if (thresholds < 2) throw std::invalid_argument("thresholds must be at least 2 (0 and 1)");
  if (max_keypoints < 1) throw std::invalid_argument("max_keypoints must be at least 1");
}

FeaturePair MakeFeaturePair(const features::FeatureOptions& pair) {
  return {features::CreateDetector(pair), features::CreateDescriptor(pair)};
}

DescribedImage DetectAndDescribe(const cv::Mat& image, const FeaturePair& pair, int max_keypoints) {
  if (image.empty() || image.type() != CV_8UC1) {
    throw std::invalid_argument("descriptor evaluation needs a non-empty 8-bit grey image");
  }
  DescribedImage described;
  described.norm = pair.descriptor.norm;
  pair.detector->detect(image, described.keypoints);
  cv::KeyPointsFilter::retainBest(described.keypoints, max_keypoints);
  pair.descriptor.extractor->compute(image, described.keypoints, described.descriptors);
  return described;
}

DescribedImage DetectAndDescribe(const cv::Mat& image, const features::FeatureOptions& pair,
                                 int max_keypoints) {
  return DetectAndDescribe(image, MakeFeaturePair(pair), max_keypoints);
}

DescriptorPrecisionRecall PrecisionRecall(const DescribedImage& reference,
                                          const DescribedImage& test,
                                          const KeypointTransfer& transfer,
                                          const DescriptorPrecisionRecallOptions& options) {
  options.Validate();
  if (reference.norm != test.norm || (!reference.descriptors.empty() && !test.descriptors.empty() &&
                                      (reference.descriptors.type() != test.descriptors.type() ||
                                       reference.descriptors.cols != test.descriptors.cols))) {
    throw std::invalid_argument("reference and test descriptors are not of one kind");
  }
  if (static_cast<std::size_t>(reference.descriptors.rows) != reference.keypoints.size() ||
      static_cast<std::size_t>(test.descriptors.rows) != test.keypoints.size()) {
    throw std::invalid_argument("every key point needs one descriptor row");
  }

  // Two nearest test descriptors of every reference descriptor.
  std::vector<std::vector<cv::DMatch>> neighbours;
  if (!reference.descriptors.empty() && !test.descriptors.empty()) {
    cv::BFMatcher(reference.norm).knnMatch(reference.descriptors, test.descriptors, neighbours, 2);
  }

  DescriptorPrecisionRecall result;
  std::vector<CarriedMatch> matches;
  for (std::size_t i = 0; i < reference.keypoints.size(); ++i) {
    const std::optional<cv::Point2f> carried = transfer.Transfer(i, reference.keypoints[i].pt);
    if (!carried) continue;
    ++result.reference_keypoints;
    const bool possible = std::any_of(
        test.keypoints.begin(), test.keypoints.end(),
        [&](const cv::KeyPoint& k) { return IsWithin(k.pt, *carried, options.epsilon); });
    result.correct_possible += possible ? 1 : 0;
    if (i >= neighbours.size() || neighbours[i].empty()) continue;
    CarriedMatch match;
    match.d1 = neighbours[i][0].distance;
    if (neighbours[i].size() > 1) match.d2 = neighbours[i][1].distance;
    match.correct =
        IsWithin(test.keypoints[neighbours[i][0].trainIdx].pt, *carried, options.epsilon);
    matches.push_back(match);
  }

  for (int k = 0; k < options.thresholds; ++k) {
    PrecisionRecallPoint point;
    point.threshold = static_cast<double>(k) / (options.thresholds - 1);
    for (const CarriedMatch& match : matches) {
      // With a single test descriptor there is no second neighbour: every t > 0 selects it.
      const bool selected = point.threshold > 0 && match.d1 < point.threshold * match.d2;
      point.selected += selected ? 1 : 0;
      point.correct += selected && match.correct ? 1 : 0;
    }
    point.precision = point.selected > 0 ? static_cast<double>(point.correct) / point.selected : 1;
    point.recall = result.correct_possible > 0
                       ? static_cast<double>(point.correct) / result.correct_possible
                       : 0;
    result.curve.push_back(point);
  }
  result.auc = AreaUnderPrecisionRecall(result.curve);
  return result;
}

double AreaUnderPrecisionRecall(const std::vector<PrecisionRecallPoint>& curve) {
  std::vector<PrecisionRecallPoint> by_recall = curve;
  std::stable_sort(by_recall.begin(), by_recall.end(),
                   [](const PrecisionRecallPoint& a, const PrecisionRecallPoint& b) {
                     return a.recall < b.recall;
                   });
  double area = 0;
  for (std::size_t k = 1; k < by_recall.size(); ++k) {
    area += (by_recall[k].recall - by_recall[k - 1].recall) *
            (by_recall[k].precision + by_recall[k - 1].precision) / 2;
  }
  return area;
}

}  // namespace stereo_fabmap_slam::evaluation
