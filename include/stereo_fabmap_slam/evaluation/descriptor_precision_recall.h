#pragma once

#include <vector>

#include <opencv2/features2d.hpp>

#include "stereo_fabmap_slam/evaluation/keypoint_transfer.h"
#include "stereo_fabmap_slam/features/feature_factory.h"
#include "stereo_fabmap_slam/features/features_options.h"

namespace stereo_fabmap_slam::evaluation {

// Key points of one image with one descriptor row each (row i describes keypoints[i]).
struct DescribedImage {
  std::vector<cv::KeyPoint> keypoints;
  cv::Mat descriptors;
  int norm = cv::NORM_HAMMING;  // how the descriptors compare
};

struct DescriptorPrecisionRecallOptions {
  double epsilon = 2.5;      // [px] a match is correct within this distance of the true position
  int thresholds = 101;      // ratio thresholds t, evenly from 0 to 1
  int max_keypoints = 1000;  // strongest key points kept per image, so pairs compare alike

  void Validate() const;  // throws std::invalid_argument naming the bad value
};

// One point of the curve: matches whose nearest-neighbour distance ratio d1 / d2 is below t.
struct PrecisionRecallPoint {
  double threshold = 0;
  // correct / selected; 1 when nothing is selected (no match made, none wrong), so that the
  // curve starts at (recall 0, precision 1) and its area is that of the matches actually made.
  double precision = 1;
  double recall = 0;  // correct / correct_possible; 0 when nothing is possible
  int selected = 0;   // matches passing the ratio test (of key points the geometry carries)
  int correct = 0;
};

struct DescriptorPrecisionRecall {
  std::vector<PrecisionRecallPoint> curve;  // threshold ascending
  double auc = 0;
  int reference_keypoints = 0;  // described reference key points the geometry carries
  int correct_possible = 0;     // of those, the ones with a test key point within epsilon
};

// A detector and a descriptor extractor, made once. Making BRISK builds its sampling pattern,
// which costs more than describing an image: timed with every image, it would count too.
struct FeaturePair {
  cv::Ptr<cv::FeatureDetector> detector;
  features::DescriptorKind descriptor;
};
// Throws std::invalid_argument for an unknown or unavailable detector/descriptor.
FeaturePair MakeFeaturePair(const features::FeatureOptions& pair);

// Detects with the pair's detector (keeping the max_keypoints strongest) and describes with its
// descriptor (which may drop key points near the border). Throws std::invalid_argument for an
// image that is not 8-bit grey.
DescribedImage DetectAndDescribe(const cv::Mat& image, const FeaturePair& pair, int max_keypoints);
// The same with a pair made for this image only.
DescribedImage DetectAndDescribe(const cv::Mat& image, const features::FeatureOptions& pair,
                                 int max_keypoints);

// Nearest-neighbour matching of every reference descriptor against the test descriptors,
// selected by d1 < t * d2 with t swept from 0 to 1, judged by where `transfer` carries the
// reference key point. Throws std::invalid_argument if the descriptors differ in type or norm.
DescriptorPrecisionRecall PrecisionRecall(const DescribedImage& reference,
                                          const DescribedImage& test,
                                          const KeypointTransfer& transfer,
                                          const DescriptorPrecisionRecallOptions& options);

// Area under precision over recall by the trapezoid rule, the points taken in order of recall.
// A curve that never reaches recall 1 has the area up to its highest recall, so a descriptor
// that finds few correct matches scores low even at precision 1.
double AreaUnderPrecisionRecall(const std::vector<PrecisionRecallPoint>& curve);

}  // namespace stereo_fabmap_slam::evaluation
