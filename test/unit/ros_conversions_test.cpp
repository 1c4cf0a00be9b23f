#include "ros_conversions.h"

#include <gtest/gtest.h>
#include <opencv2/core.hpp>

#include "stereo_fabmap_slam/datasets/euroc_sequence.h"
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

TEST(RosConversions, MalformedImagesAreToldApart) {
  cv::Mat image(48, 64, CV_8UC1, cv::Scalar(7));
  sensor_msgs::ImagePtr message = ToMono8ImageMessage(image, ToRosTime(5), "cam0");
  EXPECT_EQ(MalformedImageReason(*message), "");
  sensor_msgs::Image truncated = *message;
  truncated.data.resize(truncated.data.size() / 2);
  EXPECT_NE(MalformedImageReason(truncated).find("1536 bytes of data for 48 rows of 64 bytes"),
            std::string::npos)
      << MalformedImageReason(truncated);
  sensor_msgs::Image short_step = *message;
  short_step.encoding = "bgr8";  // 64 pixels of 3 bytes need 192 bytes a row
  EXPECT_NE(MalformedImageReason(short_step).find("step of 64 bytes for rows of 192"),
            std::string::npos);
  sensor_msgs::Image empty = *message;
  empty.width = 0;
  EXPECT_NE(MalformedImageReason(empty), "");
  sensor_msgs::Image odd = *message;
  odd.encoding = "my_own_format";  // unknown to sensor_msgs: size checked only
  EXPECT_EQ(MalformedImageReason(odd), "");
}

TEST(RosConversions, PoseRoundTrip) {
  Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
  pose.linear() = Eigen::AngleAxisd(0.7, Eigen::Vector3d(1, 2, 3).normalized()).toRotationMatrix();
  pose.translation() = Eigen::Vector3d(1.5, -2.0, 0.25);
  EXPECT_TRUE(FromPoseMessage(ToPoseMessage(pose)).isApprox(pose, 1e-12));
  EXPECT_TRUE(FromTransformMessage(ToTransformMessage(pose)).isApprox(pose, 1e-12));
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
  const datasets::EurocSequence sequence =
      datasets::EurocSequence::Open(EurocSequencePath("V101_micro"));
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
  const datasets::StereoImages raw = sequence.LoadStereoPair(10);
  cv::Mat l1, r1, l2, r2;
  from_yaml.Rectify(raw.left, raw.right, &l1, &r1);
  from_info.Rectify(raw.left, raw.right, &l2, &r2);
  EXPECT_EQ(cv::norm(l1, l2, cv::NORM_INF), 0);
  EXPECT_EQ(cv::norm(r1, r2, cv::NORM_INF), 0);

  sensor_msgs::CameraInfo fisheye = left;
  fisheye.distortion_model = "equidistant";
  EXPECT_THROW(FromCameraInfo(fisheye), std::invalid_argument);
}

map::Keyframe ExampleKeyframe() {
  map::Keyframe keyframe;
  keyframe.id = 41;
  keyframe.timestamp = 1403636584.763555584;
  keyframe.T_world_camera.linear() =
      Eigen::AngleAxisd(0.3, Eigen::Vector3d(0, 1, 1).normalized()).toRotationMatrix();
  keyframe.T_world_camera.translation() = Eigen::Vector3d(2.0, -1.0, 0.5);
  keyframe.starts_new_segment = true;
  features::StereoFeatures& f = keyframe.features;
  for (int i = 0; i < 5; ++i) {
    f.keypoints.emplace_back(10.5f + 100 * i, 20.25f + 50 * i, 7.0f);
    f.u_right.push_back(i == 2 ? -1.0f : 5.5f + 100 * i);
    f.points.emplace_back(0.1 * i, -0.2 * i, 1.0 + i);
    keyframe.map_point_ids.push_back(i == 2 ? -1 : 1000 + i);
  }
  f.descriptors = cv::Mat(5, 64, CV_8U);
  cv::randu(f.descriptors, 0, 256);
  keyframe.place_descriptors = cv::Mat(7, 64, CV_8U);
  cv::randu(keyframe.place_descriptors, 0, 256);
  return keyframe;
}

TEST(RosConversions, KeyframeRoundTrip) {
  const map::Keyframe keyframe = ExampleKeyframe();
  const geometry::StereoCamera camera{cv::Size(752, 480), 458.0, 457.0, 367.0, 248.0, 0.11};
  const stereo_fabmap_slam::Keyframe message = ToKeyframeMessage(keyframe, camera, "odom");
  EXPECT_EQ(message.header.frame_id, "odom");
  const map::Keyframe back = FromKeyframeMessage(message);
  EXPECT_EQ(back.id, keyframe.id);
  EXPECT_NEAR(back.timestamp, keyframe.timestamp, 1e-6);  // ROS time holds nanoseconds
  EXPECT_TRUE(back.T_world_camera.isApprox(keyframe.T_world_camera, 1e-12));
  EXPECT_EQ(back.starts_new_segment, keyframe.starts_new_segment);
  ASSERT_EQ(back.features.size(), keyframe.features.size());
  for (std::size_t i = 0; i < keyframe.features.size(); ++i) {
    EXPECT_EQ(back.features.keypoints[i].pt, keyframe.features.keypoints[i].pt);
    EXPECT_EQ(back.features.u_right[i], keyframe.features.u_right[i]);
    // Points travel as float32: within a micrometre at these ranges.
    EXPECT_LT((back.features.points[i] - keyframe.features.points[i]).norm(), 1e-6);
  }
  EXPECT_EQ(back.map_point_ids, keyframe.map_point_ids);
  EXPECT_EQ(cv::norm(back.features.descriptors, keyframe.features.descriptors, cv::NORM_L1), 0);
  ASSERT_EQ(back.place_descriptors.size(), keyframe.place_descriptors.size());
  EXPECT_EQ(back.place_descriptors.type(), CV_8U);
  EXPECT_EQ(cv::norm(back.place_descriptors, keyframe.place_descriptors, cv::NORM_L1), 0);
  const geometry::StereoCamera camera_back = CameraOfKeyframe(message);
  EXPECT_EQ(camera_back.size, camera.size);
  EXPECT_EQ(camera_back.fx, camera.fx);
  EXPECT_EQ(camera_back.baseline, camera.baseline);
}

TEST(RosConversions, KeyframeWithInconsistentArraysIsRefused) {
  const geometry::StereoCamera camera{cv::Size(752, 480), 458.0, 457.0, 367.0, 248.0, 0.11};
  stereo_fabmap_slam::Keyframe message = ToKeyframeMessage(ExampleKeyframe(), camera, "odom");
  message.v.pop_back();
  EXPECT_THROW(FromKeyframeMessage(message), std::invalid_argument);
  message = ToKeyframeMessage(ExampleKeyframe(), camera, "odom");
  message.place_descriptors.pop_back();  // no longer whole rows
  EXPECT_THROW(FromKeyframeMessage(message), std::invalid_argument);
}

TEST(RosConversions, KeyframeUpdateRoundTrip) {
  map::KeyframeUpdate update;
  Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
  pose.translation() = Eigen::Vector3d(0.5, 0.25, -3.0);
  update.keyframe_poses.emplace_back(7, pose);
  update.keyframe_poses.emplace_back(8, Eigen::Isometry3d::Identity());
  update.point_positions.emplace_back(123456789012, Eigen::Vector3d(1.0, 2.0, 3.0));
  update.removed_points = {5, 6};
  const map::KeyframeUpdate back = FromKeyframeUpdateMessage(ToKeyframeUpdateMessage(update));
  ASSERT_EQ(back.keyframe_poses.size(), 2u);
  EXPECT_EQ(back.keyframe_poses[0].first, 7);
  EXPECT_TRUE(back.keyframe_poses[0].second.isApprox(pose, 1e-12));
  ASSERT_EQ(back.point_positions.size(), 1u);
  EXPECT_EQ(back.point_positions[0].first, 123456789012);
  EXPECT_EQ(back.point_positions[0].second, Eigen::Vector3d(1.0, 2.0, 3.0));
  EXPECT_EQ(back.removed_points, update.removed_points);

  stereo_fabmap_slam::KeyframeUpdate broken = ToKeyframeUpdateMessage(update);
  broken.keyframe_ids.pop_back();
  EXPECT_THROW(FromKeyframeUpdateMessage(broken), std::invalid_argument);
}

TEST(RosConversions, LoopEdgeRoundTrip) {
  map::LoopEdge edge;
  edge.query_id = 120;
  edge.match_id = 7;
  edge.T_match_query.linear() = Eigen::AngleAxisd(0.1, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  edge.T_match_query.translation() = Eigen::Vector3d(0.3, -0.1, 0.05);
  for (int r = 0; r < 6; ++r) {
    for (int c = 0; c < 6; ++c) edge.information(r, c) = r == c ? 100.0 + r : 0.5 * (r + c);
  }
  edge.inliers = 87;
  edge.shared_points = {{1201, 35}, {1202, 36}, {1250, 90}};
  edge.probability = 0.93;
  const map::LoopEdge back = FromLoopEdgeMessage(ToLoopEdgeMessage(edge));
  EXPECT_EQ(back.shared_points, edge.shared_points);
  EXPECT_EQ(back.query_id, 120);
  EXPECT_EQ(back.match_id, 7);
  EXPECT_TRUE(back.T_match_query.isApprox(edge.T_match_query, 1e-12));
  EXPECT_EQ(back.information, edge.information);  // row-major, element by element
  EXPECT_EQ(back.inliers, 87);
  EXPECT_EQ(back.probability, 0.93);
}

}  // namespace
}  // namespace stereo_fabmap_slam::test
