// The StereoTracker and Backend nodelets on a real bag: odometry for nearly every frame,
// keyframes on their topic, and the same final pose as the offline runner within 5 cm.
#include <cstdlib>
#include <map>
#include <mutex>
#include <string>

#include <gtest/gtest.h>
#include <nav_msgs/Odometry.h>
#include <ros/ros.h>
#include <stereo_fabmap_slam/Keyframe.h>

#include "ros_conversions.h"
#include "stereo_fabmap_slam/evaluation/trajectory_io.h"
#include "test_support.h"

namespace stereo_fabmap_slam::test {
namespace {

TEST(EurocOdometry, BagThroughNodeletsMatchesOfflineRunner) {
  const std::string asl = EurocSequencePath("MH01_first10s");
  TemporaryDirectory temp;
  const std::string bag = temp.path() + "/mh01.bag";
  std::string output;
  ASSERT_EQ(RunCommand(std::string(EUROC_TO_BAG_BIN) + " " + asl + " " + bag + " 2>&1", &output), 0)
      << output;
  ASSERT_EQ(RunCommand(std::string(RUN_DATASET_BIN) + " " + asl + " --quiet --output " +
                           temp.path() + "/offline 2>&1",
                       &output),
            0)
      << output;
  const evaluation::Trajectory offline =
      evaluation::ReadTumTrajectory(temp.path() + "/offline/odometry.txt");  // odom frame

  std::mutex mutex;
  std::map<std::int64_t, Eigen::Isometry3d> online;  // by stamp [ns]
  int keyframes = 0;
  ros::NodeHandle node;
  const ros::Subscriber odometry_subscriber = node.subscribe<nav_msgs::Odometry>(
      "/odometry", 1000, [&](const nav_msgs::OdometryConstPtr& message) {
        std::lock_guard<std::mutex> lock(mutex);
        online[ros_conversions::ToNanoseconds(message->header.stamp)] =
            ros_conversions::FromPoseMessage(message->pose.pose);
      });
  const ros::Subscriber keyframe_subscriber = node.subscribe<stereo_fabmap_slam::Keyframe>(
      "/keyframes", 1000, [&](const stereo_fabmap_slam::KeyframeConstPtr&) {
        std::lock_guard<std::mutex> lock(mutex);
        ++keyframes;
      });
  ros::AsyncSpinner spinner(2);
  spinner.start();
  // Blocks until the bag has played (the player is required: its end ends the launch).
  const int status =
      std::system(("roslaunch --wait stereo_fabmap_slam euroc_bag.launch bag:=" + bag + " > " +
                   temp.path() + "/roslaunch.log 2>&1")
                      .c_str());
  EXPECT_EQ(status, 0) << ReadTextFile(temp.path() + "/roslaunch.log");
  ros::WallDuration(1.0).sleep();
  spinner.stop();

  std::lock_guard<std::mutex> lock(mutex);
  RecordProperty("odometry_messages", static_cast<int>(online.size()));
  RecordProperty("keyframes", keyframes);
  EXPECT_GE(online.size(), 190u) << ReadTextFile(temp.path() + "/roslaunch.log");  // 95 % of 200
  EXPECT_GT(keyframes, 5);
  ASSERT_GE(online.size(), 2u);

  // Both runs start their world at their first tracked frame; compare the motion from the
  // online run's first to its last frame.
  const auto offline_pose = [&](std::int64_t stamp_ns) {
    for (const evaluation::StampedPose& p : offline) {
      if (std::llabs(static_cast<std::int64_t>(std::llround(p.timestamp * 1e9)) - stamp_ns) < 1000)
        return p.pose;
    }
    ADD_FAILURE() << "offline trajectory has no pose at " << stamp_ns;
    return Eigen::Isometry3d::Identity();
  };
  const auto first = online.begin(), last = std::prev(online.end());
  const Eigen::Isometry3d online_motion = first->second.inverse() * last->second;
  const Eigen::Isometry3d offline_motion =
      offline_pose(first->first).inverse() * offline_pose(last->first);
  const double difference = (online_motion.translation() - offline_motion.translation()).norm();
  RecordProperty("final_pose_difference_m", std::to_string(difference));
  EXPECT_LT(difference, 0.05);
}

}  // namespace
}  // namespace stereo_fabmap_slam::test

int main(int argc, char** argv) {
  testing::InitGoogleTest(&argc, argv);
  ros::init(argc, argv, "euroc_odometry_test");
  return RUN_ALL_TESTS();
}
