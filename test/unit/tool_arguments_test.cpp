// Every command-line tool the same way: -h and --help print usage and exit 0, an unknown
// option exits 2 with usage, an input with nothing in it is an error, and a sequence too short
// for an ATE still gets its outputs.
#include <filesystem>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "test_support.h"

namespace stereo_fabmap_slam::test {
namespace {

const std::vector<std::string>& Tools() {
  static const std::vector<std::string> tools = {
      BENCHMARK_FABMAP_BIN, BENCHMARK_POSE_GRAPH_BIN,    BENCHMARK_RELOCALIZATION_BIN,
      EUROC_TO_BAG_BIN,     EVALUATE_DESCRIPTORS_BIN,    EVALUATE_PLACE_RECOGNITION_BIN,
      EVALUATE_PNP_BIN,     EVALUATE_RELOCALIZATION_BIN, EVALUATE_TRAJECTORY_BIN,
      FABMAP_MATCH_BIN,     MAKE_SYNTHETIC_SEQUENCE_BIN, RUN_DATASET_BIN,
      TRAIN_FABMAP_BIN,
  };
  return tools;
}

TEST(ToolArguments, HelpPrintsUsageAndExitsZero) {
  for (const std::string& tool : Tools()) {
    for (const char* help : {" -h", " --help"}) {
      std::string output;
      EXPECT_EQ(RunCommand(tool + help + " 2>/dev/null", &output), 0) << tool << help;
      EXPECT_EQ(output.rfind("usage: ", 0), 0u) << tool << help << ": " << output;
    }
  }
}

TEST(ToolArguments, UnknownOptionsExitTwoWithUsage) {
  for (const std::string& tool : Tools()) {
    for (const char* option : {" --no-such-option", " -x"}) {
      std::string output;
      // A benchmark that ran anyway would take minutes and exit 0: the status says it did not.
      EXPECT_EQ(RunCommand(tool + option + " 2>&1", &output), 2) << tool << option;
      EXPECT_NE(output.find("unknown option"), std::string::npos) << tool << ": " << output;
      EXPECT_NE(output.find("usage: "), std::string::npos) << tool << ": " << output;
    }
  }
}

TEST(ToolArguments, AnEmptyFolderIsAnError) {
  TemporaryDirectory temp;
  std::string output;
  EXPECT_NE(RunCommand(std::string(FABMAP_MATCH_BIN) + " " + temp.path() + " 2>/dev/null", &output),
            0);
  EXPECT_EQ(output, "") << "no CSV header for nothing";
  EXPECT_NE(RunCommand(std::string(FABMAP_MATCH_BIN) + " " + temp.path() + " 2>&1", &output), 0);
  EXPECT_NE(output.find("no images"), std::string::npos) << output;
}

// MH01's first stereo pair alone, with its ground truth: the run writes its files and says why
// there is no ATE instead of failing.
TEST(ToolArguments, OneFrameSequenceGetsItsOutputs) {
  namespace fs = std::filesystem;
  TemporaryDirectory temp;
  const fs::path source = EurocSequencePath("MH01_first10s") + "/mav0";
  const fs::path mav0 = fs::path(temp.path()) / "one/mav0";
  for (const char* camera : {"cam0", "cam1"}) {
    fs::create_directories(mav0 / camera / "data");
    fs::copy_file(source / camera / "sensor.yaml", mav0 / camera / "sensor.yaml");
    const std::string rows = ReadTextFile((source / camera / "data.csv").string());
    const std::size_t second = rows.find('\n', rows.find('\n') + 1);
    const std::string first_two_lines = rows.substr(0, second + 1);  // header and one frame
    WriteTextFile((mav0 / camera / "data.csv").string(), first_two_lines);
    const std::string name =
        first_two_lines.substr(first_two_lines.find(',', first_two_lines.find('\n')) + 1);
    const std::string file = name.substr(0, name.find_first_of("\r\n"));
    fs::copy_file(source / camera / "data" / file, mav0 / camera / "data" / file);
  }
  fs::copy(source / "state_groundtruth_estimate0", mav0 / "state_groundtruth_estimate0");
  std::string output;
  ASSERT_EQ(RunCommand(std::string(RUN_DATASET_BIN) + " " + (mav0.parent_path()).string() +
                           " --quiet --no-loop-closing --output " + temp.path() + "/out 2>&1",
                       &output),
            0)
      << output;
  EXPECT_NE(output.find("\"ate_note\": \"the ATE needs at least 3 poses"), std::string::npos)
      << output;
  for (const char* file : {"summary.json", "trajectory.txt", "timing.csv"}) {
    EXPECT_TRUE(fs::exists(temp.path() + "/out/" + file)) << file;
  }
}

}  // namespace
}  // namespace stereo_fabmap_slam::test
