#include "ros_conversions.h"

#include <gtest/gtest.h>
#include <opencv2/core.hpp>

#include "stereo_fabmap_slam/io/euroc_sequence.h"
#include "test_support.h"

namespace stereo_fabmap_slam::test {
namespace {

using namespace ros_conversions;  // NOLINT: the module under test

TEST(RosConversions, TimeKeepsNanoseconds) {
  const std::int64_t stamp = 1403636584763555584;
  EXPECT_EQ(ToNanoseconds(ToRosTime(stamp)), stamp);
  EXPECT_EQ(ToRosTime(stamp).sec, 1403636584u);
  EXPECT_EQ(ToRosTime(stamp).nsec, 763555584u);
}

TEST(RosConversions, PoseRoundTrip) {
  Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
  pose.linear() = Eigen::AngleAxisd(0.7, Eigen::Vector3d(1, 2, 3).normalized()).toRotationMatrix();
  pose.translation() = Eigen::Vector3d(1.5, -2.0, 0.25);
  EXPECT_TRUE(FromPoseMessage(ToPoseMessage(pose)).isApprox(pose, 1e-12));
  EXPECT_DOUBLE_EQ(ToPoseMessage(pose).position.y, -2.0);
}

TEST(RosConversions, Mono8ImageCopiesPixels) {
  cv::Mat image(48, 64, CV_8UC1);
  cv::randu(image, 0, 255);
  const sensor_msgs::ImagePtr message = ToMono8ImageMessage(image, ToRosTime(5), "cam0");
  EXPECT_EQ(message->encoding, "mono8");
  EXPECT_EQ(message->header.frame_id, "cam0");
  EXPECT_EQ(message->width, 64u);
  ASSERT_EQ(message->data.size(), 64u * 48u);
  EXPECT_EQ(
      cv::norm(image, cv::Mat(48, 64, CV_8UC1, message->data.data(), message->step), cv::NORM_INF),
      0);
  EXPECT_THROW(ToMono8ImageMessage(cv::Mat(4, 4, CV_8UC3), ToRosTime(5), "cam0"),
               std::invalid_argument);
}

TEST(RosConversions, CameraInfoPairGivesTheSameRectification) {
  const io::EurocSequence sequence = io::EurocSequence::Open(EurocSequencePath("V101_micro"));
  const camera::StereoRectifier from_yaml =
      camera::StereoRectifier::FromCalibration(sequence.calibration());
  const sensor_msgs::CameraInfo left = ToCameraInfo(from_yaml.left_parameters(), "cam0");
  const sensor_msgs::CameraInfo right = ToCameraInfo(from_yaml.right_parameters(), "cam1");
  EXPECT_EQ(left.width, 752u);
  EXPECT_EQ(right.distortion_model, "plumb_bob");
  const camera::StereoRectifier from_info =
      RectifierFromCameraInfo(left, right, sequence.calibration().left.T_body_camera);
  EXPECT_DOUBLE_EQ(from_info.camera().fx, from_yaml.camera().fx);
  EXPECT_DOUBLE_EQ(from_info.camera().baseline, from_yaml.camera().baseline);
  EXPECT_TRUE(from_info.T_body_rectified_left().isApprox(from_yaml.T_body_rectified_left(), 1e-12));
  // Same maps: the same rectified pixels.
  const io::StereoImages raw = sequence.LoadStereoPair(10);
  cv::Mat l1, r1, l2, r2;
  from_yaml.Rectify(raw.left, raw.right, &l1, &r1);
  from_info.Rectify(raw.left, raw.right, &l2, &r2);
  EXPECT_EQ(cv::norm(l1, l2, cv::NORM_INF), 0);
  EXPECT_EQ(cv::norm(r1, r2, cv::NORM_INF), 0);

  sensor_msgs::CameraInfo fisheye = left;
  fisheye.distortion_model = "equidistant";
  EXPECT_THROW(FromCameraInfo(fisheye), std::invalid_argument);
}

}  // namespace
}  // namespace stereo_fabmap_slam::test
