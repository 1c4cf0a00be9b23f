// A misspelt private parameter (~features/max_featurs) is refused like the same typo in YAML,
// with the accepted keys, and the launch ends (its nodelet loaders are required) rather than
// leaving the manager, Backend and LoopDetector running as if all were well. A map file or mode
// the LoopDetector refuses at start is another matter: the odometry runs on, the LoopDetector
// with an empty map in mapping mode, saying so, and its services answer.
#include <sys/wait.h>

#include <cstdlib>
#include <filesystem>
#include <string>
#include <vector>

#include <atomic>
#include <mutex>
#include <thread>

#include <gtest/gtest.h>
#include <nav_msgs/Odometry.h>
#include <ros/ros.h>
#include <stereo_fabmap_slam/MapFile.h>
#include <stereo_fabmap_slam/SetMode.h>

#include "euroc_bag_fixture.h"
#include "test_support.h"

namespace stereo_fabmap_slam::test {
namespace {

// Runs one of this folder's launch files that must end by itself, the graph refusing to start;
// returns its output (empty, and the test fails, if it did not end).
std::string OutputOfARefusedLaunch(const std::string& launch_file) {
  TemporaryDirectory temp;
  // roslaunch on the rostest's master; `timeout` stops it if it does not end by itself (the
  // graph would otherwise run until killed, with no tracker).
  const std::string log = temp.path() + "/roslaunch.log";
  const int status = std::system(("timeout 60 roslaunch " + RepositoryRoot() + "/test/ros/" +
                                  launch_file + " > " + log + " 2>&1")
                                     .c_str());
  const std::string output = ReadTextFile(log);
  EXPECT_TRUE(WIFEXITED(status)) << output;
  EXPECT_NE(WEXITSTATUS(status), 124) << "the launch kept running:\n" << output;
  // Nothing of the graph is left running (the master may list a node a moment longer than
  // its process lives, so ask the processes).
  std::string processes;
  EXPECT_NE(RunCommand("pgrep -af '__name:=(stereo_fabmap_slam_manager|backend|loop_detector)'",
                       &processes),
            0)
      << processes;
  return output;
}

TEST(Misconfiguration, MisspeltPrivateParameterEndsTheLaunchWithItsName) {
  const std::string output = OutputOfARefusedLaunch("misspelt_parameter.launch");
  EXPECT_NE(output.find("unknown parameter(s) /stereo_tracker/features/max_featurs"),
            std::string::npos)
      << output;
  EXPECT_NE(output.find("max_features"), std::string::npos) << "the accepted keys are listed";
  ros::param::del("/stereo_tracker");  // the next launch would meet it too
}

// Outside the sections too (~tf_rate, ~rate, ~queue_size were read with a default, so a typo
// was ignored).
TEST(Misconfiguration, MisspeltParameterOutsideTheSectionsEndsTheLaunchWithItsName) {
  const std::string output = OutputOfARefusedLaunch("misspelt_top_level_parameter.launch");
  EXPECT_NE(output.find("unknown parameter(s) /stereo_tracker/queue_sise"), std::string::npos)
      << output;
  EXPECT_NE(output.find("queue_size"), std::string::npos) << "the accepted names are listed";
  ros::param::del("/stereo_tracker");
}

// save_map:= (or map_file:=, mode:=localization) with loop_closing:=false: no LoopDetector runs
// to keep the map, so the launch ends saying so instead of dropping the request.
TEST(Misconfiguration, AMapAskedForWithoutLoopClosingEndsTheLaunchSayingWhy) {
  const std::string output = OutputOfARefusedLaunch("map_without_loop_closing.launch");
  EXPECT_NE(output.find("need loop closing (the LoopDetector keeps the map)"), std::string::npos)
      << output;
  ros::param::del("/stereo_tracker");
}

// A damaged ~map_file and ~mode:=bogus: before, the LoopDetector threw from onInit and the
// manager died of a segmentation fault (5 of 5 tries), taking the tracker with it.
TEST(Misconfiguration, ARefusedMapFileOrModeLeavesTheGraphRunning) {
  TemporaryDirectory temp;
  const std::string bag = temp.path() + "/mh01.bag";
  WriteEurocSubsetBag("MH01_first10s", bag);
  const std::string damaged = temp.path() + "/damaged.map";
  WriteTextFile(damaged, "not a map at all");
  std::atomic<int> odometry{0};
  ros::NodeHandle node;
  const ros::Subscriber subscriber = node.subscribe<nav_msgs::Odometry>(
      "/odometry", 1000, [&](const nav_msgs::OdometryConstPtr&) { ++odometry; });
  ros::AsyncSpinner spinner(1);
  spinner.start();
  // The services while the bag plays: the LoopDetector is up and in mapping mode.
  stereo_fabmap_slam::SetMode mode;
  stereo_fabmap_slam::MapFile load;
  std::atomic<bool> called{false};
  std::thread caller([&] {
    if (!ros::service::waitForService("/set_mode", ros::Duration(60))) return;
    mode.request.mode = "mapping";
    load.request.path = damaged;
    called = ros::service::call("/set_mode", mode) && ros::service::call("/load_map", load);
  });
  const std::string log = temp.path() + "/roslaunch.log";
  // At the end the map goes to a folder that is not there, and the run to one that is made.
  const std::string unwritable = temp.path() + "/no/such/folder/end.map";
  const std::string run = temp.path() + "/run";
  const int status =
      std::system(("timeout 120 roslaunch --wait stereo_fabmap_slam euroc_bag.launch "
                   "exit_at_end:=true visualizer:=false mode:=bogus map_file:=" +
                   damaged + " save_map:=" + unwritable + " output:=" + run + " bag:=" + bag +
                   " > " + log + " 2>&1")
                      .c_str());
  caller.join();
  spinner.stop();
  const std::string output = ReadTextFile(log);
  ASSERT_TRUE(WIFEXITED(status)) << output;
  EXPECT_EQ(WEXITSTATUS(status), 0) << output;
  EXPECT_NE(output.find("~mode 'bogus' is not a mode (mapping, localization): mapping"),
            std::string::npos)
      << output;
  EXPECT_NE(output.find("~map_file refused:"), std::string::npos) << output;
  EXPECT_NE(output.find("running with an empty map in mapping mode"), std::string::npos);
  // The bag player ends the launch (exit_at_end: it is required); nothing else ended.
  const std::size_t died = output.find("has died");
  ASSERT_NE(died, std::string::npos) << output;
  EXPECT_NE(output.rfind("REQUIRED process [bag_player", died), std::string::npos) << output;
  EXPECT_EQ(output.find("has died", died + 1), std::string::npos) << output;
  EXPECT_GE(odometry.load(), 190) << "the odometry ran on (200 pairs)";
  ASSERT_TRUE(called) << "the LoopDetector's services answered";
  EXPECT_TRUE(mode.response.success) << mode.response.message;
  EXPECT_FALSE(load.response.success);
  EXPECT_NE(load.response.message.find("the map is unchanged"), std::string::npos)
      << load.response.message;
  // What the graph does as it shuts down is said too (rosconsole is down by then): the save
  // that failed, and the run written.
  const std::size_t save = output.find("[loop_detector] ~save_map " + unwritable + ": ");
  ASSERT_NE(save, std::string::npos) << output;
  const std::string said = output.substr(save, output.find('\n', save) - save);
  EXPECT_EQ(said.find(": saved "), std::string::npos) << said;
  RecordProperty("failed_save_at_exit", said);
  EXPECT_FALSE(std::filesystem::exists(unwritable));
  EXPECT_NE(output.find("[recorder] run written to " + run + ": "), std::string::npos) << output;
  EXPECT_TRUE(std::filesystem::exists(run + "/trajectory.txt"));
}

}  // namespace
}  // namespace stereo_fabmap_slam::test

int main(int argc, char** argv) {
  testing::InitGoogleTest(&argc, argv);
  ros::init(argc, argv, "misconfiguration_test");
  return RUN_ALL_TESTS();
}
