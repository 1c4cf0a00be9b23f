// euroc_to_bag, run as a user runs it, and its bag read back with the rosbag C++ API.
#include <string>

#include <geometry_msgs/PoseStamped.h>
#include <gtest/gtest.h>
#include <rosbag/bag.h>
#include <rosbag/view.h>
#include <sensor_msgs/CameraInfo.h>
#include <sensor_msgs/Image.h>
#include <opencv2/core.hpp>

#include "ros_conversions.h"
#include "stereo_fabmap_slam/camera/stereo_rectifier.h"
#include "stereo_fabmap_slam/datasets/euroc_sequence.h"
#include "test_support.h"

namespace stereo_fabmap_slam::test {
namespace {

TEST(EurocToBag, V101MicroReadsBackFrameForFrame) {
  const std::string asl = EurocSequencePath("V101_micro");
  const datasets::EurocSequence sequence = datasets::EurocSequence::Open(asl);
  TemporaryDirectory temp;
  const std::string bag_path = temp.path() + "/v101.bag";
  std::string output;
  ASSERT_EQ(
      RunCommand(std::string(EUROC_TO_BAG_BIN) + " " + asl + " " + bag_path + " 2>&1", &output), 0)
      << output;

  rosbag::Bag bag(bag_path, rosbag::bagmode::Read);
  std::size_t images[2] = {0, 0};
  std::size_t poses = 0, infos[2] = {0, 0};
  sensor_msgs::CameraInfoConstPtr first_info[2];
  for (const rosbag::MessageInstance& instance : rosbag::View(bag)) {
    if (instance.getTopic() == "/cam0/camera_info" || instance.getTopic() == "/cam1/camera_info") {
      const int side = instance.getTopic() == "/cam0/camera_info" ? 0 : 1;
      const auto info = instance.instantiate<sensor_msgs::CameraInfo>();
      ASSERT_TRUE(info);
      const std::size_t index = infos[side]++;
      ASSERT_LT(index, sequence.size());
      EXPECT_EQ(ros_conversions::ToNanoseconds(info->header.stamp),
                sequence.frames()[index].timestamp_ns);
      if (index == 0) first_info[side] = info;
      continue;
    }
    if (instance.getTopic() == "/ground_truth") {
      const auto pose = instance.instantiate<geometry_msgs::PoseStamped>();
      ASSERT_TRUE(pose);
      const io::StampedPose& truth = sequence.ground_truth()[poses++];
      EXPECT_NEAR(pose->header.stamp.toSec(), truth.timestamp, 1e-6);
      EXPECT_TRUE(ros_conversions::FromPoseMessage(pose->pose).isApprox(truth.pose, 1e-9));
      continue;
    }
    const int side = instance.getTopic() == "/cam0/image_raw" ? 0 : 1;
    ASSERT_TRUE(side == 0 || instance.getTopic() == "/cam1/image_raw") << instance.getTopic();
    const auto image = instance.instantiate<sensor_msgs::Image>();
    ASSERT_TRUE(image);
    const std::size_t index = images[side]++;
    ASSERT_LT(index, sequence.size());
    const datasets::StereoFrameEntry& frame = sequence.frames()[index];
    EXPECT_EQ(ros_conversions::ToNanoseconds(image->header.stamp), frame.timestamp_ns);
    EXPECT_EQ(ros_conversions::ToNanoseconds(instance.getTime()), frame.timestamp_ns);
    EXPECT_EQ(image->header.frame_id, side == 0 ? "cam0" : "cam1");
    EXPECT_EQ(image->encoding, "mono8");
    const datasets::StereoImages expected = sequence.LoadStereoPair(index);
    const cv::Mat& pixels = side == 0 ? expected.left : expected.right;
    const cv::Mat stored(static_cast<int>(image->height), static_cast<int>(image->width), CV_8UC1,
                         const_cast<std::uint8_t*>(image->data.data()), image->step);
    ASSERT_EQ(stored.size(), pixels.size());
    EXPECT_EQ(cv::norm(stored, pixels, cv::NORM_INF), 0) << "frame " << index;
  }
  EXPECT_EQ(images[0], 95u);
  EXPECT_EQ(images[1], 95u);
  EXPECT_EQ(poses, sequence.ground_truth().size());
  // The camera_info pair describes the same rectified stereo camera as the calibration.
  EXPECT_EQ(infos[0], 95u);
  EXPECT_EQ(infos[1], 95u);
  ASSERT_TRUE(first_info[0] && first_info[1]);
  const geometry::StereoCamera from_info =
      ros_conversions::RectifierFromCameraInfo(*first_info[0], *first_info[1],
                                               Eigen::Isometry3d::Identity())
          .camera();
  const geometry::StereoCamera from_calibration =
      camera::StereoRectifier::FromCalibration(sequence.calibration()).camera();
  EXPECT_NEAR(from_info.fx, from_calibration.fx, 1e-9);
  EXPECT_NEAR(from_info.cx, from_calibration.cx, 1e-9);
  EXPECT_NEAR(from_info.baseline, from_calibration.baseline, 1e-9);

  // What `rosbag info` shows a user (the Python tool, no master needed).
  ASSERT_EQ(RunCommand("rosbag info --yaml " + bag_path + " 2>&1", &output), 0) << output;
  for (const std::string& entry :
       {std::string("topic: /cam0/image_raw\n      type: sensor_msgs/Image\n      messages: 95"),
        std::string("topic: /cam1/image_raw\n      type: sensor_msgs/Image\n      messages: 95"),
        "topic: /ground_truth\n      type: geometry_msgs/PoseStamped\n      messages: " +
            std::to_string(poses)}) {
    EXPECT_NE(output.find(entry), std::string::npos) << entry << "\nnot in:\n" << output;
  }
}

TEST(EurocToBag, ReportsBadInput) {
  TemporaryDirectory temp;
  std::string output;
  EXPECT_EQ(RunCommand(std::string(EUROC_TO_BAG_BIN) + " " + temp.path() + " " + temp.path() +
                           "/x.bag 2>&1",
                       &output),
            1);
  EXPECT_NE(output.find("not an EuRoC ASL folder"), std::string::npos) << output;
  EXPECT_EQ(RunCommand(std::string(EUROC_TO_BAG_BIN) + " 2>&1", &output), 2);
}

}  // namespace
}  // namespace stereo_fabmap_slam::test
