// A misspelt private parameter (~features/max_featurs) is refused like the same typo in YAML,
// with the accepted keys, and the launch ends (its nodelet loaders are required) rather than
// leaving the manager, Backend and LoopDetector running as if all were well.
#include <sys/wait.h>

#include <cstdlib>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <ros/ros.h>

#include "test_support.h"

namespace stereo_fabmap_slam::test {
namespace {

TEST(Misconfiguration, MisspeltPrivateParameterEndsTheLaunchWithItsName) {
  TemporaryDirectory temp;
  // roslaunch on the rostest's master; `timeout` stops it if it does not end by itself (the
  // graph would otherwise run until killed, with no tracker).
  const std::string log = temp.path() + "/roslaunch.log";
  const int status = std::system(("timeout 60 roslaunch " + RepositoryRoot() +
                                  "/test/ros/misspelt_parameter.launch > " + log + " 2>&1")
                                     .c_str());
  const std::string output = ReadTextFile(log);
  ASSERT_TRUE(WIFEXITED(status)) << output;
  EXPECT_NE(WEXITSTATUS(status), 124) << "the launch kept running:\n" << output;
  EXPECT_NE(output.find("unknown parameter(s) /stereo_tracker/features/max_featurs"),
            std::string::npos)
      << output;
  EXPECT_NE(output.find("max_features"), std::string::npos) << "the accepted keys are listed";
  // Nothing of the graph is left running (the master may list a node a moment longer than
  // its process lives, so ask the processes).
  std::string processes;
  EXPECT_NE(RunCommand("pgrep -af '__name:=(stereo_fabmap_slam_manager|backend|loop_detector)'",
                       &processes),
            0)
      << processes;
}

}  // namespace
}  // namespace stereo_fabmap_slam::test

int main(int argc, char** argv) {
  testing::InitGoogleTest(&argc, argv);
  ros::init(argc, argv, "misconfiguration_test");
  return RUN_ALL_TESTS();
}
