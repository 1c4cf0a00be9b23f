// The core library's modules form a stack (docs/architecture.md): a module includes nothing from
// a module above it. The order is kept here as data; every header and source of a core module is
// checked against it, and so are the layers outside the core: the ROS helpers (src/ros) and the
// nodelets include the SLAM's modules up to pipeline and never the evaluation or the datasets
// (the nodelets do not load them), the tools anything.
#include <algorithm>
#include <filesystem>
#include <fstream>
#include <map>
#include <regex>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "test_support.h"

namespace stereo_fabmap_slam::test {
namespace {

// Lowest first.
const std::vector<std::string> kModuleOrder = {
    "concurrency", "io",      "geometry",          "camera",         "features", "map",
    "odometry",    "backend", "place_recognition", "relocalization", "dense",    "pipeline",
    "evaluation",  "datasets"};

// The folders of src/ outside the core, and the highest core module each may include.
const std::map<std::string, std::string> kOutsideTheCore = {
    {"ros", "pipeline"}, {"nodelets", "pipeline"}, {"tools", "datasets"}};

int Rank(const std::string& module) {
  const auto outside = kOutsideTheCore.find(module);
  if (outside != kOutsideTheCore.end()) return Rank(outside->second);
  const auto it = std::find(kModuleOrder.begin(), kModuleOrder.end(), module);
  return it == kModuleOrder.end() ? -1 : static_cast<int>(it - kModuleOrder.begin());
}

// The modules a line includes that lie above `module`; an unknown module counts as above.
std::vector<std::string> IncludesAbove(const std::string& module, const std::string& line) {
  static const std::regex include(R"(#\s*include\s*[<"]stereo_fabmap_slam/([a-z_]+)/)");
  std::vector<std::string> above;
  std::smatch match;
  if (std::regex_search(line, match, include)) {
    const std::string included = match[1].str();
    if (Rank(included) < 0 || Rank(included) > Rank(module)) above.push_back(included);
  }
  return above;
}

TEST(ModuleOrder, TheCheckSeesAnIncludeFromAbove) {
  // So that the test below can fail: odometry may include geometry, not backend.
  EXPECT_TRUE(
      IncludesAbove("odometry", "#include \"stereo_fabmap_slam/geometry/pnp_ransac.h\"").empty());
  EXPECT_EQ(IncludesAbove("odometry", "#include \"stereo_fabmap_slam/backend/pose_graph.h\""),
            std::vector<std::string>{"backend"});
  EXPECT_EQ(IncludesAbove("io", "#include <stereo_fabmap_slam/unknown/x.h>"),
            std::vector<std::string>{"unknown"});
  // The nodelets may use the stages, not the evaluation or the datasets.
  EXPECT_TRUE(
      IncludesAbove("nodelets", "#include \"stereo_fabmap_slam/pipeline/place_stage.h\"").empty());
  EXPECT_EQ(IncludesAbove("ros", "#include \"stereo_fabmap_slam/datasets/euroc_sequence.h\""),
            std::vector<std::string>{"datasets"});
  EXPECT_EQ(IncludesAbove("nodelets", "#include \"stereo_fabmap_slam/evaluation/trajectory.h\""),
            std::vector<std::string>{"evaluation"});
}

TEST(ModuleOrder, NoFileIncludesAModuleAboveIt) {
  const std::string root = RepositoryRoot();
  int files_checked = 0;
  for (const std::string& folder : {root + "/include/stereo_fabmap_slam", root + "/src"}) {
    for (const auto& entry : std::filesystem::directory_iterator(folder)) {
      if (!entry.is_directory()) continue;
      const std::string module = entry.path().filename().string();
      ASSERT_GE(Rank(module), 0) << "module " << module << " is not in the order";
      for (const auto& file : std::filesystem::recursive_directory_iterator(entry.path())) {
        if (!file.is_regular_file()) continue;
        std::ifstream stream(file.path());
        std::string line;
        int line_number = 0;
        while (std::getline(stream, line)) {
          ++line_number;
          for (const std::string& above : IncludesAbove(module, line)) {
            ADD_FAILURE() << file.path().string() << ":" << line_number << ": " << module
                          << " includes " << above << ", which lies above it";
          }
        }
        ++files_checked;
      }
    }
  }
  EXPECT_GT(files_checked, 150);
}

}  // namespace
}  // namespace stereo_fabmap_slam::test
