#include "stereo_fabmap_slam/camera/stereo_rectifier.h"

#include <algorithm>
#include <cmath>
#include <vector>

#include <gtest/gtest.h>
#include <opencv2/calib3d.hpp>
#include <opencv2/features2d.hpp>

#include "stereo_fabmap_slam/datasets/euroc_sequence.h"
#include "test_support.h"

namespace stereo_fabmap_slam::test {
namespace {

using camera::StereoRectifier;

struct StereoMatch {
  cv::Point2f left, right;
};

// Cross-checked SIFT matches between two images: each is the other's nearest neighbour. SIFT
// because its key points are refined to sub-pixel positions, so that a vertical disparity of a
// fraction of a pixel can be seen at all (FAST/ORB corners sit on whole pixels).
std::vector<StereoMatch> CrossCheckedMatches(const cv::Mat& left, const cv::Mat& right) {
  cv::Ptr<cv::SIFT> sift = cv::SIFT::create(1000);
  std::vector<cv::KeyPoint> left_points, right_points;
  cv::Mat left_descriptors, right_descriptors;
  sift->detectAndCompute(left, cv::noArray(), left_points, left_descriptors);
  sift->detectAndCompute(right, cv::noArray(), right_points, right_descriptors);
  cv::BFMatcher matcher(cv::NORM_L2, /*crossCheck=*/true);
  std::vector<cv::DMatch> matches;
  matcher.match(left_descriptors, right_descriptors, matches);
  std::vector<StereoMatch> result;
  for (const cv::DMatch& m : matches) {
    result.push_back({left_points[m.queryIdx].pt, right_points[m.trainIdx].pt});
  }
  return result;
}

double Median(std::vector<double> values) {
  std::nth_element(values.begin(), values.begin() + values.size() / 2, values.end());
  return values[values.size() / 2];
}

class RectificationOnEuroc : public ::testing::Test {
 protected:
  RectificationOnEuroc()
      : sequence_(datasets::EurocSequence::Open(EurocSequencePath("MH01_first10s"))),
        rectifier_(StereoRectifier::FromCalibration(sequence_.calibration())) {}

  datasets::EurocSequence sequence_;
  StereoRectifier rectifier_;
};

TEST_F(RectificationOnEuroc, RectifiedModelIsPlausible) {
  const geometry::StereoCamera& camera = rectifier_.camera();
  EXPECT_EQ(camera.size, cv::Size(752, 480));
  EXPECT_NEAR(camera.baseline, 0.110, 0.002);
  // alpha = 0 crops away the distorted border, so the focal length shrinks a little.
  EXPECT_GT(camera.fx, 350.0);
  EXPECT_LT(camera.fx, 460.0);
  // The rectified left camera looks almost where the raw one does (a rotation of a degree or so).
  const Eigen::Matrix3d relative = sequence_.calibration().left.T_body_camera.linear().transpose() *
                                   rectifier_.T_body_rectified_left().linear();
  EXPECT_LT(Eigen::AngleAxisd(relative).angle(), 3.0 * M_PI / 180.0);
  EXPECT_LT((rectifier_.T_body_rectified_left().translation() -
             sequence_.calibration().left.T_body_camera.translation())
                .norm(),
            1e-12);
}

TEST_F(RectificationOnEuroc, MatchesLieOnTheSameRowWithPositiveDepth) {
  const cv::Matx34d P_left = rectifier_.left_parameters().P;
  const cv::Matx34d P_right = rectifier_.right_parameters().P;
  std::vector<double> rectified_dy, raw_dy;
  int epipolar_matches = 0, positive_depth = 0;
  for (const std::size_t frame : {0u, 50u, 100u, 150u, 199u}) {
    const datasets::StereoImages raw = sequence_.LoadStereoPair(frame);
    cv::Mat left, right;
    rectifier_.Rectify(raw.left, raw.right, &left, &right);
    for (const StereoMatch& m : CrossCheckedMatches(left, right)) {
      const double dy = std::abs(m.left.y - m.right.y);
      rectified_dy.push_back(dy);
      if (dy > 1.0) continue;  // not on the epipolar line: a wrong match, no depth to check
      ++epipolar_matches;
      cv::Mat point;
      cv::triangulatePoints(P_left, P_right, std::vector<cv::Point2f>{m.left},
                            std::vector<cv::Point2f>{m.right}, point);
      const double depth = point.at<float>(2) / point.at<float>(3);
      if (depth > 0) ++positive_depth;
    }
    for (const StereoMatch& m : CrossCheckedMatches(raw.left, raw.right)) {
      raw_dy.push_back(std::abs(m.left.y - m.right.y));
    }
  }
  ASSERT_GT(rectified_dy.size(), 1000u);
  const double median_rectified = Median(rectified_dy);
  const double median_raw = Median(raw_dy);
  RecordProperty("median_vertical_disparity_rectified", std::to_string(median_rectified));
  RecordProperty("median_vertical_disparity_raw", std::to_string(median_raw));
  EXPECT_LT(median_rectified, 0.5);
  // Rectification is what puts matches on one row: the raw images are clearly worse.
  EXPECT_GT(median_raw, 2.0 * median_rectified);
  // Cross-checked matches on the right row are nearly all true ones, in front of the cameras.
  EXPECT_GE(positive_depth, 0.98 * epipolar_matches)
      << positive_depth << " of " << epipolar_matches;
}

// With the front end's helper thread the two images are remapped in bands of rows on two
// threads: the same pixels as one cv::remap per image.
TEST_F(RectificationOnEuroc, RemappingInBandsOnTwoThreadsGivesTheSameImages) {
  concurrency::HelperThread helper;
  for (const std::size_t frame : {0u, 120u}) {
    const datasets::StereoImages raw = sequence_.LoadStereoPair(frame);
    cv::Mat left, right, left_banded, right_banded;
    rectifier_.Rectify(raw.left, raw.right, &left, &right);
    for (int run = 0; run < 5; ++run) {
      rectifier_.Rectify(raw.left, raw.right, &left_banded, &right_banded, &helper);
      ASSERT_EQ(left_banded.size(), left.size());
      ASSERT_EQ(right_banded.size(), right.size());
      EXPECT_EQ(cv::norm(left_banded, left, cv::NORM_INF), 0.0) << frame;
      EXPECT_EQ(cv::norm(right_banded, right, cv::NORM_INF), 0.0) << frame;
      left_banded.release();
      right_banded.release();
    }
  }
}

TEST_F(RectificationOnEuroc, ConfigFileGivesTheSameModelAsSensorYaml) {
  const camera::StereoCalibration from_config =
      camera::ReadStereoCalibrationYaml(RepositoryRoot() + "/config/euroc_stereo.yaml");
  const StereoRectifier other = StereoRectifier::FromCalibration(from_config);
  EXPECT_DOUBLE_EQ(other.camera().fx, rectifier_.camera().fx);
  EXPECT_DOUBLE_EQ(other.camera().cx, rectifier_.camera().cx);
  EXPECT_DOUBLE_EQ(other.camera().cy, rectifier_.camera().cy);
  EXPECT_DOUBLE_EQ(other.camera().baseline, rectifier_.camera().baseline);
  EXPECT_TRUE(other.T_body_rectified_left().isApprox(rectifier_.T_body_rectified_left(), 1e-12));
}

// ROS's base_link for EuRoC (T_body_base in the config): level, looking where the cameras look.
// At the first ground-truth pose of both sequences (MH01 on the floor, V101 hovering) the
// base's z axis is within 5 degrees of the world's up (measured: 1.5 and 3), and the left camera
// looks 20 degrees below the base's x axis (its mounting), within 3 degrees.
TEST(EurocCalibration, BaseFrameIsLevelAndLooksForward) {
  const camera::StereoCalibration calibration =
      camera::ReadStereoCalibrationYaml(RepositoryRoot() + "/config/euroc_stereo.yaml");
  for (const char* name : {"MH01_first10s", "V101_micro"}) {
    const datasets::EurocSequence sequence = datasets::EurocSequence::Open(EurocSequencePath(name));
    ASSERT_TRUE(sequence.has_ground_truth());
    const Eigen::Matrix3d R_world_base =
        sequence.ground_truth().front().pose.rotation() * calibration.T_body_base.rotation();
    const double tilt_deg = std::acos((R_world_base * Eigen::Vector3d::UnitZ()).z()) * 180.0 / M_PI;
    RecordProperty(std::string("base_tilt_deg_") + name, std::to_string(tilt_deg));
    EXPECT_LT(tilt_deg, 5.0) << name;
  }
  const Eigen::Isometry3d T_base_camera =
      calibration.T_body_base.inverse() *
      StereoRectifier::FromCalibration(calibration).T_body_rectified_left();
  const Eigen::Vector3d optical_axis = T_base_camera.rotation() * Eigen::Vector3d::UnitZ();
  const double below_deg = -std::asin(optical_axis.z()) * 180.0 / M_PI;
  EXPECT_NEAR(below_deg, 20.0, 3.0) << optical_axis.transpose();
  EXPECT_NEAR(optical_axis.y(), 0.0, std::sin(3.0 * M_PI / 180.0));
  // A file without T_body_base: the body is the base.
  TemporaryDirectory temp;
  camera::StereoCalibration plain = calibration;
  plain.T_body_base = Eigen::Isometry3d::Identity();
  camera::WriteStereoCalibrationYaml(plain, temp.path() + "/plain.yaml");
  EXPECT_TRUE(camera::ReadStereoCalibrationYaml(temp.path() + "/plain.yaml")
                  .T_body_base.isApprox(Eigen::Isometry3d::Identity(), 1e-12));
  camera::WriteStereoCalibrationYaml(calibration, temp.path() + "/euroc.yaml");
  EXPECT_TRUE(camera::ReadStereoCalibrationYaml(temp.path() + "/euroc.yaml")
                  .T_body_base.isApprox(calibration.T_body_base, 1e-12));
}

TEST_F(RectificationOnEuroc, RejectsImagesOfTheWrongSizeOrType) {
  const cv::Mat small(240, 376, CV_8UC1, cv::Scalar(0));
  const cv::Mat good(480, 752, CV_8UC1, cv::Scalar(0));
  const cv::Mat colour(480, 752, CV_8UC3, cv::Scalar(0));
  cv::Mat left, right;
  EXPECT_THROW(rectifier_.Rectify(small, good, &left, &right), std::invalid_argument);
  EXPECT_THROW(rectifier_.Rectify(good, colour, &left, &right), std::invalid_argument);
  EXPECT_THROW(rectifier_.Rectify(good, cv::Mat(), &left, &right), std::invalid_argument);
}

TEST(StereoCamera, ProjectAndTriangulateAreInverse) {
  geometry::StereoCamera camera{cv::Size(752, 480), 435.0, 435.0, 370.0, 250.0, 0.11};
  const Eigen::Vector3d point(0.4, -0.3, 3.5);
  const Eigen::Vector3d pixels = camera.Project(point);
  EXPECT_NEAR(pixels.x() - pixels.z(), 435.0 * 0.11 / 3.5, 1e-12);
  EXPECT_TRUE(
      camera.Triangulate(pixels.x(), pixels.y(), pixels.x() - pixels.z()).isApprox(point, 1e-12));
}

TEST(StereoRectifierParameters, RejectsAPairThatIsNotRectified) {
  camera::RectificationParameters left{cv::Size(752, 480),
                                       cv::Matx33d::eye(),
                                       {0, 0, 0, 0},
                                       cv::Matx33d::eye(),
                                       cv::Matx34d(400, 0, 370, 0, 0, 400, 250, 0, 0, 0, 1, 0)};
  camera::RectificationParameters right = left;
  right.P(0, 3) = -400 * 0.11;
  EXPECT_NO_THROW(StereoRectifier::FromParameters(left, right, Eigen::Isometry3d::Identity()));
  right.P(1, 2) = 260;  // rows differ: not rectified
  EXPECT_THROW(StereoRectifier::FromParameters(left, right, Eigen::Isometry3d::Identity()),
               std::invalid_argument);
  right.P(1, 2) = 250;
  right.P(0, 3) = 400 * 0.11;  // right camera on the left
  EXPECT_THROW(StereoRectifier::FromParameters(left, right, Eigen::Isometry3d::Identity()),
               std::invalid_argument);
}

}  // namespace
}  // namespace stereo_fabmap_slam::test
