// Descriptor precision-recall (issue 13) on cases whose answer is known: an image against
// itself, against a copy shifted by a known number of pixels (with the right and a wrong
// geometry), a hand-made curve's area, and the geometries on their own.
#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "stereo_fabmap_slam/evaluation/descriptor_case.h"
#include "stereo_fabmap_slam/evaluation/descriptor_precision_recall.h"
#include "stereo_fabmap_slam/evaluation/homography_transfer.h"
#include "stereo_fabmap_slam/evaluation/illumination_change.h"
#include "stereo_fabmap_slam/evaluation/pose_interpolation.h"
#include "stereo_fabmap_slam/evaluation/stereo_pose_transfer.h"
#include "stereo_fabmap_slam/io/input_error.h"
#include "test_support.h"

namespace stereo_fabmap_slam::evaluation {
namespace {

const std::string kOpencvData = "/usr/share/doc/opencv-doc/examples/data";

cv::Mat Graf1() {
  const cv::Mat image = cv::imread(kOpencvData + "/graf1.png", cv::IMREAD_GRAYSCALE);
  if (image.empty()) throw std::runtime_error("opencv-doc's graf1.png is missing");
  return image;
}

features::FeatureOptions Pair(const std::string& detector, const std::string& descriptor) {
  features::FeatureOptions pair;
  pair.detector = detector;
  pair.descriptor = descriptor;
  return pair;
}

// The image moved by whole pixels: every pixel keeps its value, the uncovered strip is black.
cv::Mat Shifted(const cv::Mat& image, int dx, int dy) {
  cv::Mat shifted;
  const cv::Matx23d move(1, 0, dx, 0, 1, dy);
  cv::warpAffine(image, shifted, move, image.size(), cv::INTER_NEAREST, cv::BORDER_CONSTANT, 0);
  return shifted;
}

cv::Matx33d Translation(double dx, double dy) { return {1, 0, dx, 0, 1, dy, 0, 0, 1}; }

// Binary descriptors whose key points a whole-pixel shift moves by whole pixels (AGAST corners;
// BRISK and ORB sample the image at the key point), and one from a scale pyramid.
const std::vector<features::FeatureOptions>& Pairs() {
  static const std::vector<features::FeatureOptions> pairs = {
      Pair("AGAST", "BRISK"), Pair("FAST", "ORB"), Pair("ORB", "ORB"), Pair("SIFT", "SIFT")};
  return pairs;
}

TEST(DescriptorPrecisionRecall, AnImageAgainstItselfHasPrecisionOneAtEveryRecall) {
  const cv::Mat image = Graf1();
  const HomographyTransfer identity(cv::Matx33d::eye(), image.size());
  DescriptorPrecisionRecallOptions options;
  for (const features::FeatureOptions& pair : Pairs()) {
    SCOPED_TRACE(pair.detector + "/" + pair.descriptor);
    const DescribedImage described = DetectAndDescribe(image, pair, options.max_keypoints);
    const DescriptorPrecisionRecall pr = PrecisionRecall(described, described, identity, options);
    ASSERT_EQ(pr.curve.size(), 101u);
    EXPECT_GT(pr.reference_keypoints, 300)
        << "graf1 is textured: a test with few points says little";
    // Every key point lies on itself, so every one is possible.
    EXPECT_EQ(pr.correct_possible, pr.reference_keypoints);
    for (const PrecisionRecallPoint& point : pr.curve) {
      // A selected match has d1 = 0 < t * d2: its own copy, unique, hence correct. Exactly 1.
      EXPECT_EQ(point.precision, 1.0) << "t " << point.threshold;
      EXPECT_EQ(point.correct, point.selected);
    }
    EXPECT_EQ(pr.curve.front().selected, 0) << "t = 0 selects nothing";
    // Only key points with an exact twin descriptor elsewhere (d2 = 0) are never selected; on a
    // photo these are a few at most.
    EXPECT_GE(pr.curve.back().recall, 0.98);
    EXPECT_NEAR(pr.auc, pr.curve.back().recall, 1e-12) << "precision 1 up to the top recall";
  }
}

TEST(DescriptorPrecisionRecall, AKnownShiftIsFoundAndAWrongOneIsNot) {
  const cv::Mat image = Graf1();
  constexpr int kDx = 24, kDy = -16;  // multiples of 8: whole pixels in SIFT's first octaves too
  const cv::Mat shifted = Shifted(image, kDx, kDy);
  const HomographyTransfer right(Translation(kDx, kDy), image.size());
  const HomographyTransfer wrong(Translation(kDx + 10, kDy), image.size());
  DescriptorPrecisionRecallOptions options;
  for (const features::FeatureOptions& pair : Pairs()) {
    SCOPED_TRACE(pair.detector + "/" + pair.descriptor);
    const DescribedImage reference = DetectAndDescribe(image, pair, options.max_keypoints);
    const DescribedImage test = DetectAndDescribe(shifted, pair, options.max_keypoints);
    const DescriptorPrecisionRecall found = PrecisionRecall(reference, test, right, options);
    // The shift leaves the key points that stay in view (all but a strip of 24 and 16 px)
    // where they were in the content.
    EXPECT_GT(found.reference_keypoints, 300);
    EXPECT_GE(found.correct_possible, 0.9 * found.reference_keypoints);
    const PrecisionRecallPoint& low_t = found.curve[50];  // t = 0.5: unambiguous matches
    EXPECT_GT(low_t.selected, 0);
    EXPECT_GE(low_t.precision, 0.98) << "selected " << low_t.selected;
    // Near 1, not 1: descriptors of points near the black strip and, for pyramid detectors, of
    // points on levels where the shift is not whole pixels change.
    EXPECT_GE(found.curve.back().recall, 0.85);
    EXPECT_GE(found.auc, 0.8);

    const DescriptorPrecisionRecall missed = PrecisionRecall(reference, test, wrong, options);
    EXPECT_GT(missed.curve.back().selected, 0) << "matches are made, just judged wrong";
    for (const PrecisionRecallPoint& point : missed.curve) {
      // A match passing t <= 0.8 is the key point's own copy, 10 px (4 epsilon) from where the
      // wrong geometry looks. Ambiguous matches (t near 1) land anywhere and on graf's repeated
      // windows may hit that spot by chance: a handful of hundreds.
      if (point.threshold <= 0.8) {
        EXPECT_EQ(point.correct, 0) << "t " << point.threshold;
      } else {
        EXPECT_LE(point.correct, 0.01 * point.selected) << "t " << point.threshold;
      }
    }
    EXPECT_LT(missed.auc, 0.001);
    EXPECT_LT(missed.curve.back().recall, 0.01 * found.curve.back().recall + 0.01);
  }
}

TEST(DescriptorPrecisionRecall, AreaOfAHandMadeCurve) {
  std::vector<PrecisionRecallPoint> curve(4);
  // Out of recall order on purpose: the area is taken along recall.
  curve[0].recall = 1.0, curve[0].precision = 0.5;
  curve[1].recall = 0.0, curve[1].precision = 1.0;
  curve[2].recall = 0.5, curve[2].precision = 1.0;
  curve[3].recall = 0.5, curve[3].precision = 1.0;  // a repeated point adds nothing
  // 0.5 * 1 + 0.5 * (1 + 0.5) / 2
  EXPECT_DOUBLE_EQ(AreaUnderPrecisionRecall(curve), 0.875);
  EXPECT_EQ(AreaUnderPrecisionRecall({}), 0.0);
  EXPECT_EQ(AreaUnderPrecisionRecall({curve[1]}), 0.0);
}

TEST(DescriptorPrecisionRecall, NothingSelectedIsPrecisionOneAndNothingPossibleIsRecallZero) {
  const cv::Mat image = Graf1();
  const features::FeatureOptions pair = Pair("ORB", "ORB");
  const DescribedImage described = DetectAndDescribe(image, pair, 1000);
  // A homography that carries everything out of view: no key point takes part.
  const HomographyTransfer away(Translation(1e5, 0), image.size());
  const DescriptorPrecisionRecall pr = PrecisionRecall(described, described, away, {});
  EXPECT_EQ(pr.reference_keypoints, 0);
  EXPECT_EQ(pr.correct_possible, 0);
  for (const PrecisionRecallPoint& point : pr.curve) {
    EXPECT_EQ(point.selected, 0);
    EXPECT_EQ(point.precision, 1.0);
    EXPECT_EQ(point.recall, 0.0);
  }
}

TEST(DescriptorPrecisionRecall, RejectsDescriptorsOfDifferentKinds) {
  const cv::Mat image = Graf1();
  const DescribedImage orb = DetectAndDescribe(image, Pair("ORB", "ORB"), 200);
  const DescribedImage sift = DetectAndDescribe(image, Pair("SIFT", "SIFT"), 200);
  const HomographyTransfer identity(cv::Matx33d::eye(), image.size());
  EXPECT_THROW(PrecisionRecall(orb, sift, identity, {}), std::invalid_argument);
  DescriptorPrecisionRecallOptions bad;
  bad.epsilon = 0;
  EXPECT_THROW(PrecisionRecall(orb, orb, identity, bad), std::invalid_argument);
}

TEST(HomographyTransfer, MapsPointsAndKnowsTheView) {
  const cv::Matx33d H(2, 0, 10, 0, 2, 20, 0, 0, 1);
  const HomographyTransfer transfer(H, cv::Size(100, 100));
  const std::optional<cv::Point2f> inside = transfer.Transfer(0, {5, 7});
  ASSERT_TRUE(inside);
  EXPECT_FLOAT_EQ(inside->x, 20);
  EXPECT_FLOAT_EQ(inside->y, 34);
  EXPECT_FALSE(transfer.Transfer(0, {45, 7})) << "x = 100: just outside";
  EXPECT_FALSE(transfer.Transfer(0, {-6, 7}));
}

TEST(HomographyTransfer, ReadsOxfordTextAndOpencvXml) {
  const cv::Matx33d graf = ReadHomography(kOpencvData + "/H1to3p.xml");
  EXPECT_DOUBLE_EQ(graf(0, 0), 7.6285898e-01);
  EXPECT_DOUBLE_EQ(graf(1, 2), -7.6999973e+01);
  EXPECT_DOUBLE_EQ(graf(2, 2), 1.0);
  test::TemporaryDirectory temp;
  test::WriteTextFile(temp.path() + "/H1to2p", " 1 0 5\n 0 1 -3\n 0 0 1\n");
  const cv::Matx33d text = ReadHomography(temp.path() + "/H1to2p");
  EXPECT_EQ(text(0, 2), 5);
  EXPECT_EQ(text(1, 2), -3);
  test::WriteTextFile(temp.path() + "/short", "1 0 5 0 1\n");
  EXPECT_THROW(ReadHomography(temp.path() + "/short"), io::InputError);
  EXPECT_THROW(ReadHomography(temp.path() + "/missing"), io::InputError);
}

TEST(StereoPoseTransfer, ProjectsTheMovedPoint) {
  geometry::StereoCamera camera;
  camera.size = cv::Size(752, 480);
  camera.fx = camera.fy = 400;
  camera.cx = 376;
  camera.cy = 240;
  camera.baseline = 0.11;
  // The test camera 0.2 m to the right of the reference: a point 2 m ahead on the optical
  // axis appears 400 * 0.2 / 2 = 40 px left of centre.
  Eigen::Isometry3d T_test_reference = Eigen::Isometry3d::Identity();
  T_test_reference.translation() = Eigen::Vector3d(-0.2, 0, 0);
  const StereoPoseTransfer transfer(
      camera, {Eigen::Vector3d(0, 0, 2), std::nullopt, Eigen::Vector3d(0, 0, -1)},
      T_test_reference);
  const std::optional<cv::Point2f> moved = transfer.Transfer(0, {376, 240});
  ASSERT_TRUE(moved);
  EXPECT_NEAR(moved->x, 336, 1e-4);
  EXPECT_NEAR(moved->y, 240, 1e-4);
  EXPECT_FALSE(transfer.Transfer(1, {0, 0})) << "no depth";
  EXPECT_FALSE(transfer.Transfer(2, {0, 0})) << "behind the camera";
  EXPECT_FALSE(transfer.Transfer(3, {0, 0})) << "no such key point";
}

TEST(StereoPoseTransfer, TriangulatesARenderedPlane) {
  // A textured plane at constant disparity 20 px: the right image is the left moved 20 px left.
  const cv::Mat left = Graf1()(cv::Rect(0, 0, 640, 480)).clone();
  const cv::Mat right = Shifted(left, -20, 0);
  geometry::StereoCamera camera;
  camera.size = left.size();
  camera.fx = camera.fy = 400;
  camera.cx = 320;
  camera.cy = 240;
  camera.baseline = 0.1;
  const features::FeatureOptions pair = Pair("AGAST", "BRISK");
  const DescribedImage described = DetectAndDescribe(left, pair, 1000);
  const std::vector<std::optional<Eigen::Vector3d>> points =
      TriangulateKeypoints(left, right, described.keypoints, pair, {}, camera);
  ASSERT_EQ(points.size(), described.keypoints.size());
  int with_depth = 0;
  for (const std::optional<Eigen::Vector3d>& point : points) {
    if (!point) continue;
    ++with_depth;
    EXPECT_NEAR(point->z(), 400 * 0.1 / 20, 0.05) << "depth 2 m, a tenth of a pixel of disparity";
  }
  EXPECT_GT(with_depth, static_cast<int>(points.size()) / 2);
}

TEST(IlluminationChange, RendersGainGammaAndALight) {
  const cv::Mat flat(100, 200, CV_8UC1, cv::Scalar(200));
  IlluminationChange gain;
  gain.gain = 0.5;
  EXPECT_EQ(cv::mean(ApplyIlluminationChange(flat, gain))[0], 100);
  IlluminationChange gamma;
  gamma.gamma = 2;
  EXPECT_NEAR(cv::mean(ApplyIlluminationChange(flat, gamma))[0], 255 * std::pow(200 / 255., 2),
              0.5);
  IlluminationChange light;
  light.light_min = 0.25;  // dark on the left, bright on the right
  const cv::Mat lit = ApplyIlluminationChange(flat, light);
  EXPECT_EQ(lit.at<std::uint8_t>(50, 0), 50);
  EXPECT_EQ(lit.at<std::uint8_t>(50, 199), 200);
  EXPECT_LT(lit.at<std::uint8_t>(50, 90), lit.at<std::uint8_t>(50, 110));
  light.light_angle_deg = 90;  // dark on top
  const cv::Mat from_below = ApplyIlluminationChange(flat, light);
  EXPECT_EQ(from_below.at<std::uint8_t>(0, 100), 50);
  EXPECT_EQ(from_below.at<std::uint8_t>(99, 100), 200);
  EXPECT_EQ(StandardIlluminationChanges().size(), 6u);
}

TEST(PoseInterpolation, HalfwayBetweenTwoPoses) {
  Trajectory trajectory(2);
  trajectory[0].timestamp = 1.0;
  trajectory[1].timestamp = 1.01;
  trajectory[1].pose.translation() = Eigen::Vector3d(1, 0, 0);
  trajectory[1].pose.linear() = Eigen::AngleAxisd(0.2, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  const std::optional<Eigen::Isometry3d> half = InterpolatePose(trajectory, 1.005, 0.05);
  ASSERT_TRUE(half);
  EXPECT_NEAR(half->translation().x(), 0.5, 1e-9);
  EXPECT_NEAR(Eigen::AngleAxisd(half->linear()).angle(), 0.1, 1e-9);
  EXPECT_FALSE(InterpolatePose(trajectory, 0.99, 0.05));
  EXPECT_FALSE(InterpolatePose(trajectory, 1.02, 0.05));
  EXPECT_FALSE(InterpolatePose(trajectory, 1.005, 0.001)) << "a gap in the ground truth";
}

}  // namespace
}  // namespace stereo_fabmap_slam::evaluation
