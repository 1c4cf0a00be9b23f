// The one rule of the house: the core library neither links a ROS library nor includes a ROS
// header. Checked on the built library (ldd) and on the sources.
#include <filesystem>
#include <fstream>
#include <regex>
#include <string>

#include <gtest/gtest.h>

#include "test_support.h"

namespace stereo_fabmap_slam::test {
namespace {

// Libraries that only exist because of ROS (Debian's ROS 1 packages).
const std::regex kRosLibrary(
    R"((libroscpp|librosbag|librostime|libcpp_common|libroscpp_serialization|libxmlrpcpp|)"
    R"(librosconsole|libcv_bridge|libtf2|libnodeletlib|libclass_loader|libimage_transport|)"
    R"(libmessage_filters|libtopic_tools|libbondcpp)\S*\.so)");

std::string LinkedLibraries(const std::string& library) {
  std::string output;
  EXPECT_EQ(RunCommand("ldd '" + library + "'", &output), 0) << output;
  return output;
}

TEST(CoreLibraryDependencies, CoreLinksNoRosLibrary) {
  const std::string linked = LinkedLibraries(STEREO_FABMAP_SLAM_CORE_LIBRARY);
  // The check is only meaningful if ldd listed the libraries we know the core uses.
  ASSERT_NE(linked.find("libopencv_core"), std::string::npos) << linked;
  std::smatch match;
  EXPECT_FALSE(std::regex_search(linked, match, kRosLibrary))
      << "core library links " << match.str() << ":\n"
      << linked;
}

TEST(CoreLibraryDependencies, PatternRecognisesRosLibraries) {
  // The same pattern does find ROS in a library that has it, so the check above can fail.
  const std::string nodelets = std::filesystem::path(STEREO_FABMAP_SLAM_CORE_LIBRARY)
                                   .replace_filename("libstereo_fabmap_slam_nodelets.so")
                                   .string();
  EXPECT_TRUE(std::regex_search(LinkedLibraries(nodelets), kRosLibrary));
}

TEST(CoreLibraryDependencies, NodeletsLinkNoDatasetsNorEvaluation) {
  // The EuRoC reader, the synthetic world and the evaluation are for tools and tests: a robot
  // running the nodelets loads none of them. Every library links with -Wl,--no-undefined, so a
  // library that used one without linking it would not link at all (checked below): what ldd
  // lists is all each one needs.
  for (const char* name : {"libstereo_fabmap_slam_nodelets.so", "libstereo_fabmap_slam_ros.so",
                           "libstereo_fabmap_slam_core.so"}) {
    const std::string library =
        std::filesystem::path(STEREO_FABMAP_SLAM_CORE_LIBRARY).replace_filename(name).string();
    const std::string linked = LinkedLibraries(library);
    ASSERT_NE(linked.find("libopencv_core"), std::string::npos) << name << ":\n" << linked;
    EXPECT_EQ(linked.find("libstereo_fabmap_slam_datasets"), std::string::npos) << name;
    EXPECT_EQ(linked.find("libstereo_fabmap_slam_evaluation"), std::string::npos) << name;
  }
}

TEST(CoreLibraryDependencies, EveryLibraryResolvesItsSymbols) {
  // ldd -r reports the symbols a library leaves undefined that none of its libraries defines.
  for (const char* name : {"libstereo_fabmap_slam_core.so", "libstereo_fabmap_slam_evaluation.so",
                           "libstereo_fabmap_slam_datasets.so", "libstereo_fabmap_slam_ros.so",
                           "libstereo_fabmap_slam_nodelets.so"}) {
    const std::string library =
        std::filesystem::path(STEREO_FABMAP_SLAM_CORE_LIBRARY).replace_filename(name).string();
    std::string output;
    EXPECT_EQ(RunCommand("ldd -r '" + library + "' 2>&1", &output), 0) << output;
    EXPECT_EQ(output.find("undefined symbol"), std::string::npos) << name << ":\n" << output;
  }
}

TEST(CoreLibraryDependencies, CoreSourcesIncludeNoRosHeader) {
  const std::regex ros_include(
      R"(#\s*include\s*[<"](ros/|rosbag/|nodelet/|pluginlib/|cv_bridge/|tf2|image_transport/|)"
      R"(message_filters/|sensor_msgs/|geometry_msgs/|std_msgs/|nav_msgs/))");
  const std::string root = RepositoryRoot();
  int files_checked = 0;
  for (const std::string folder : {"include", "src"}) {
    for (const auto& entry : std::filesystem::recursive_directory_iterator(root + "/" + folder)) {
      const std::string path = entry.path().string();
      if (!entry.is_regular_file()) continue;
      // ROS lives in the nodelets, the ROS helper library and the tools only (the tools' bag
      // writing among them).
      if (path.find("/src/nodelets/") != std::string::npos ||
          path.find("/src/ros/") != std::string::npos ||
          path.find("/src/tools/") != std::string::npos) {
        continue;
      }
      std::ifstream file(path);
      std::string line;
      while (std::getline(file, line)) {
        EXPECT_FALSE(std::regex_search(line, ros_include)) << path << ": " << line;
      }
      ++files_checked;
    }
  }
  EXPECT_GT(files_checked, 10);
}

}  // namespace
}  // namespace stereo_fabmap_slam::test
