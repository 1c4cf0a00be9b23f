// The Backend unloaded (rosnode kill) and loaded again into the running manager while
// MH01_first10s plays at half speed: the tracker keeps publishing odometry through it, the
// restarted Backend says which keyframes it does not have, and keyframe_updates (its bundle
// adjustment) resume for the keyframes after the restart.
#include <atomic>
#include <cstdlib>
#include <mutex>
#include <set>
#include <string>
#include <thread>
#include <vector>

#include <gtest/gtest.h>
#include <nav_msgs/Odometry.h>
#include <ros/ros.h>
#include <rosgraph_msgs/Log.h>
#include <stereo_fabmap_slam/KeyframeUpdate.h>

#include "euroc_bag_fixture.h"
#include "test_support.h"

namespace stereo_fabmap_slam::test {
namespace {

TEST(Restart, BackendUnloadedAndLoadedAgainWhileTheBagPlays) {
  TemporaryDirectory temp;
  const std::string bag = temp.path() + "/mh01.bag";
  WriteEurocSubsetBag("MH01_first10s", bag);

  std::mutex mutex;
  std::set<double> odometry_stamps;
  std::vector<double> update_wall_times;
  std::vector<std::string> log;
  ros::NodeHandle node;
  const ros::Subscriber odometry = node.subscribe<nav_msgs::Odometry>(
      "/odometry", 1000, [&](const nav_msgs::OdometryConstPtr& m) {
        std::lock_guard<std::mutex> lock(mutex);
        odometry_stamps.insert(m->header.stamp.toSec());
      });
  const ros::Subscriber updates = node.subscribe<stereo_fabmap_slam::KeyframeUpdate>(
      "/keyframe_updates", 1000, [&](const stereo_fabmap_slam::KeyframeUpdateConstPtr&) {
        std::lock_guard<std::mutex> lock(mutex);
        update_wall_times.push_back(ros::WallTime::now().toSec());
      });
  const ros::Subscriber rosout =
      node.subscribe<rosgraph_msgs::Log>("/rosout", 1000, [&](const rosgraph_msgs::LogConstPtr& m) {
        std::lock_guard<std::mutex> lock(mutex);
        log.push_back(m->msg);
      });
  ros::AsyncSpinner spinner(2);
  spinner.start();
  const auto odometry_count = [&] {
    std::lock_guard<std::mutex> lock(mutex);
    return odometry_stamps.size();
  };

  // 10 s of images at half speed: 20 s of playback.
  std::thread launch([&] {
    std::system(("roslaunch --wait stereo_fabmap_slam euroc_bag.launch exit_at_end:=true "
                 "visualizer:=false rate:=0.5 bag:=" +
                 bag + " > " + temp.path() + "/roslaunch.log 2>&1")
                    .c_str());
  });
  const ros::WallTime deadline = ros::WallTime::now() + ros::WallDuration(60);
  while (odometry_count() < 40 && ros::WallTime::now() < deadline) ros::WallDuration(0.1).sleep();
  ASSERT_GE(odometry_count(), 40u) << ReadTextFile(temp.path() + "/roslaunch.log");

  // Unload the Backend for 2 s: 1 s of images at half speed, 20 frames.
  EXPECT_EQ(std::system("rosnode kill /backend > /dev/null 2>&1"), 0);
  const std::size_t odometry_at_kill = odometry_count();
  ros::WallDuration(2.0).sleep();
  const std::size_t odometry_while_away = odometry_count() - odometry_at_kill;
  // Loaded again into the running manager, with the parameters the launch left on the server.
  const double restart_time = ros::WallTime::now().toSec();
  std::thread loader([&] {
    std::system(("rosrun nodelet nodelet load stereo_fabmap_slam/Backend "
                 "stereo_fabmap_slam_manager __name:=backend > " +
                 temp.path() + "/backend.log 2>&1")
                    .c_str());
  });
  launch.join();  // the bag ends the launch
  std::system("rosnode kill /backend > /dev/null 2>&1");
  loader.join();
  ros::WallDuration(0.5).sleep();
  spinner.stop();

  std::lock_guard<std::mutex> lock(mutex);
  RecordProperty("odometry", static_cast<int>(odometry_stamps.size()));
  RecordProperty("odometry_while_backend_away", static_cast<int>(odometry_while_away));
  // The tracker did not wait for the Backend: odometry throughout (1 s of images while away).
  EXPECT_GE(odometry_while_away, 15u);
  EXPECT_GE(odometry_stamps.size(), 195u);
  int updates_after_restart = 0;
  for (const double t : update_wall_times) updates_after_restart += t > restart_time + 0.5 ? 1 : 0;
  RecordProperty("keyframe_updates_after_restart", updates_after_restart);
  EXPECT_GE(updates_after_restart, 3) << "bundle adjustment resumes after the restart";
  bool said_what_it_lost = false;
  for (const std::string& message : log) {
    said_what_it_lost |=
        message.find("the keyframes before it are not in this Backend's map") != std::string::npos;
  }
  EXPECT_TRUE(said_what_it_lost) << ReadTextFile(temp.path() + "/roslaunch.log");
  // Unloading at the end aborts nothing (see load_test).
  EXPECT_EQ(ReadTextFile(temp.path() + "/roslaunch.log").find("terminate called"),
            std::string::npos)
      << ReadTextFile(temp.path() + "/roslaunch.log");
}

}  // namespace
}  // namespace stereo_fabmap_slam::test

int main(int argc, char** argv) {
  testing::InitGoogleTest(&argc, argv);
  ros::init(argc, argv, "restart_test");
  return RUN_ALL_TESTS();
}
