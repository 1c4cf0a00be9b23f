// Converts V101_micro with euroc_to_bag, plays it with `roslaunch stereo_fabmap_slam
// play_bag.launch`, and checks that every image arrives, in order, with its stamp.
#include <cstdlib>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

#include <gtest/gtest.h>
#include <ros/ros.h>
#include <rosgraph_msgs/Clock.h>
#include <sensor_msgs/Image.h>

#include "ros_conversions.h"
#include "stereo_fabmap_slam/datasets/euroc_sequence.h"
#include "test_support.h"

namespace stereo_fabmap_slam::test {
namespace {

class StampRecorder {
 public:
  void Record(const sensor_msgs::ImageConstPtr& image) {
    std::lock_guard<std::mutex> lock(mutex_);
    stamps_.push_back(ros_conversions::ToNanoseconds(image->header.stamp));
  }
  std::vector<std::int64_t> stamps() const {
    std::lock_guard<std::mutex> lock(mutex_);
    return stamps_;
  }

 private:
  mutable std::mutex mutex_;
  std::vector<std::int64_t> stamps_;
};

TEST(BagPlayback, EveryImageArrivesInOrder) {
  const std::string asl = EurocSequencePath("V101_micro");
  const datasets::EurocSequence sequence = datasets::EurocSequence::Open(asl);
  TemporaryDirectory temp;
  const std::string bag = temp.path() + "/v101.bag";
  std::string output;
  ASSERT_EQ(RunCommand(std::string(EUROC_TO_BAG_BIN) + " " + asl + " " + bag + " 2>&1", &output), 0)
      << output;

  ros::NodeHandle node;
  StampRecorder left, right;
  int clock_messages = 0;
  const ros::Subscriber left_subscriber =
      node.subscribe("/cam0/image_raw", 200, &StampRecorder::Record, &left);
  const ros::Subscriber right_subscriber =
      node.subscribe("/cam1/image_raw", 200, &StampRecorder::Record, &right);
  const ros::Subscriber clock_subscriber = node.subscribe<rosgraph_msgs::Clock>(
      "/clock", 10, [&](const rosgraph_msgs::ClockConstPtr&) { ++clock_messages; });
  ros::AsyncSpinner spinner(1);
  spinner.start();

  // roslaunch joins the master rostest started (ROS_MASTER_URI is set for this process).
  const int status =
      std::system(("roslaunch --wait stereo_fabmap_slam play_bag.launch rate:=4 bag:=" + bag +
                   " > " + temp.path() + "/roslaunch.log 2>&1")
                      .c_str());
  EXPECT_EQ(status, 0) << ReadTextFile(temp.path() + "/roslaunch.log");
  ros::WallDuration(1.0).sleep();  // let the last messages drain
  spinner.stop();

  std::vector<std::int64_t> expected;
  for (const datasets::StereoFrameEntry& frame : sequence.frames())
    expected.push_back(frame.timestamp_ns);
  EXPECT_EQ(left.stamps(), expected);
  EXPECT_EQ(right.stamps(), expected);
  EXPECT_GT(clock_messages, 0);
}

}  // namespace
}  // namespace stereo_fabmap_slam::test

int main(int argc, char** argv) {
  testing::InitGoogleTest(&argc, argv);
  ros::init(argc, argv, "bag_playback_test");
  return RUN_ALL_TESTS();
}
