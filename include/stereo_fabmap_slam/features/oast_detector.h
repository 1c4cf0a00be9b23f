#pragma once

#include <vector>

#include <opencv2/features2d.hpp>

namespace stereo_fabmap_slam::features {

// OpenCV's AGAST detector of type OAST_9_16 with non-maximum suppression, the same key points
// (position, response, size: checked on every image of features_test's set), in under half
// its time: the odometry's left detector (docs/benchmarks.md, "AGAST's corners from FAST's
// segment test").
//
// Why it is written here: OpenCV's OAST_9_16 tests the segment with a decision tree, pixel by
// pixel (2.4 ms on a 752 x 480 EuRoC image at threshold 20), while its FAST runs the same test
// (9 contiguous pixels of 16, strictly brighter or darker than the centre by the threshold)
// with SIMD over a row (0.4 ms): the raw corner sets are identical. What differs is what comes
// after: FAST keeps corners above their eight neighbours, AGAST keeps the strongest corner of
// each 4-connected blob of corners. So the raw corners come from cv::FAST without suppression,
// each is given the score both detectors use (the highest threshold at which it is still a
// corner), and AGAST's blob suppression is applied as OpenCV does it. Other types, or no
// suppression, go to cv::AGAST itself.
class OastDetector : public cv::AgastFeatureDetector {
 public:
  static cv::Ptr<OastDetector> create(int threshold, bool nonmax_suppression = true,
                                      DetectorType type = OAST_9_16);

  void detect(cv::InputArray image, std::vector<cv::KeyPoint>& keypoints,
              cv::InputArray mask = cv::noArray()) override;

  void setThreshold(int threshold) override { threshold_ = threshold; }
  int getThreshold() const override { return threshold_; }
  void setNonmaxSuppression(bool on) override { nonmax_suppression_ = on; }
  bool getNonmaxSuppression() const override { return nonmax_suppression_; }
  void setType(DetectorType type) override { type_ = type; }
  DetectorType getType() const override { return type_; }
  cv::String getDefaultName() const override;

 private:
  OastDetector(int threshold, bool nonmax_suppression, DetectorType type)
      : threshold_(threshold), nonmax_suppression_(nonmax_suppression), type_(type) {}

  int threshold_;
  bool nonmax_suppression_;
  DetectorType type_;
};

// The segment test's score of the corner at `centre` (9 of 16 pixels on the radius-3 circle):
// the highest threshold t at which 9 contiguous circle pixels are all brighter than the centre
// by more than t, or all darker, clamped to [threshold, 254] as OpenCV's AGAST and FAST scores
// are. `ring` holds the 16 circle offsets in the image (in order around the circle).
int SegmentTestScore(const unsigned char* centre, const int ring[16], int threshold);

// AGAST's suppression: of each group of corners joined through their left and upper
// neighbours, the strongest, with ties broken as OpenCV's AGAST breaks them.
// `corners`: integer positions in row order, each row's in column order (cv::FAST's order).
std::vector<cv::KeyPoint> KeepStrongestOfEachBlob(const std::vector<cv::KeyPoint>& corners);

}  // namespace stereo_fabmap_slam::features
