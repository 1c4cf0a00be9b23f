// Every command-line tool the same way: -h and --help print usage and exit 0, an unknown
// option exits 2 with usage, an input with nothing in it is an error, and a sequence too short
// for an ATE still gets its outputs.
#include <algorithm>
#include <cctype>
#include <filesystem>
#include <regex>
#include <set>
#include <string>
#include <utility>
#include <vector>

#include <gtest/gtest.h>

#include "test_support.h"

namespace stereo_fabmap_slam::test {
namespace {

const std::vector<std::string>& Tools() {
  static const std::vector<std::string> tools = {
      BENCHMARK_FABMAP_BIN,
      BENCHMARK_POSE_GRAPH_BIN,
      BENCHMARK_RELOCALIZATION_BIN,
      EUROC_TO_BAG_BIN,
      EVALUATE_DESCRIPTORS_BIN,
      EVALUATE_PLACE_RECOGNITION_BIN,
      EVALUATE_PNP_BIN,
      EVALUATE_RELOCALIZATION_BIN,
      EVALUATE_TRAJECTORY_BIN,
      FABMAP_MATCH_BIN,
      LOCKSTEP_PLAYER_BIN,
      MAKE_SYNTHETIC_SEQUENCE_BIN,
      RUN_DATASET_BIN,
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

// One spelling for one meaning across the tools: every flag in the usage texts, hyphenated, and
// of each group of spellings users write for the same thing at most one in use. The groups are
// the spellings other tools (evo, ORB-SLAM's examples, ROS tools) and this package's history
// used; a tool that adds `--out` or `--spacing` fails here.
TEST(ToolArguments, OneSpellingForEachFlagAcrossTheTools) {
  const std::vector<std::vector<std::string>> synonyms = {
      {"--output", "--out", "--output-dir", "--outdir", "--output-folder"},
      {"--every", "--spacing", "--step", "--stride", "--skip", "--subsample"},
      {"--config", "--cfg", "--settings", "--params"},
      {"--fabmap-config", "--fabmap-cfg", "--fabmap-settings"},
      {"--vocabulary", "--vocab", "--voc"},
      {"--gt", "--ground-truth", "--groundtruth", "--reference", "--ref"},
      {"--est", "--estimate", "--trajectory"},
      {"--json", "--as-json", "--json-output"},
      {"--quiet", "--silent"},
      {"--load-map", "--map", "--map-file"},
  };
  std::set<std::string> flags;
  const std::regex flag("--[A-Za-z][A-Za-z0-9_-]*");
  for (const std::string& tool : Tools()) {
    std::string usage;
    ASSERT_EQ(RunCommand(tool + " --help", &usage), 0) << tool;
    for (std::sregex_iterator it(usage.begin(), usage.end(), flag), end; it != end; ++it) {
      flags.insert(it->str());
    }
  }
  ASSERT_GT(flags.size(), 40u) << "the usage texts name the flags";
  for (const std::string& name : flags) {
    EXPECT_EQ(name.find('_'), std::string::npos) << name << ": flags are hyphenated";
    EXPECT_TRUE(std::none_of(name.begin(), name.end(), [](char c) { return std::isupper(c); }))
        << name << ": flags are lower case";
  }
  for (const std::vector<std::string>& group : synonyms) {
    std::vector<std::string> used;
    for (const std::string& spelling : group) {
      if (flags.count(spelling) > 0) used.push_back(spelling);
    }
    EXPECT_LE(used.size(), 1u) << "one meaning, spelt " << testing::PrintToString(used);
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

// Every tool that reads images or poses, given a folder, sequence or file with none in it:
// exit 1 and a message naming the file and what is missing (not a header, an empty table or a
// benchmark of nothing). evaluate_descriptors is left out: its inputs are fixed datasets,
// whose missing files it names.
TEST(ToolArguments, EveryInputWithNothingInItIsAnError) {
  namespace fs = std::filesystem;
  TemporaryDirectory temp;
  const fs::path source = EurocSequencePath("MH01_first10s") + "/mav0";
  const std::string asl = temp.path() + "/empty_asl", folder = temp.path() + "/empty_folder";
  for (const char* camera : {"cam0", "cam1"}) {  // calibrated cameras, a list with no image
    const fs::path mav0 = fs::path(asl) / "mav0";
    fs::create_directories(mav0 / camera / "data");
    fs::copy_file(source / camera / "sensor.yaml", mav0 / camera / "sensor.yaml");
    const std::string rows = ReadTextFile((source / camera / "data.csv").string());
    WriteTextFile((mav0 / camera / "data.csv").string(), rows.substr(0, rows.find('\n') + 1));
  }
  fs::create_directories(folder);
  const std::string poses = folder + "/poses.txt";
  WriteTextFile(poses, "# timestamp tx ty tz qx qy qz qw\n\n");
  const std::string out = " --output " + temp.path() + "/out";
  const std::string no_images_listed = "data.csv: no images listed";
  const std::vector<std::pair<std::string, std::string>> runs = {
      {std::string(RUN_DATASET_BIN) + " " + asl + out, no_images_listed},
      {std::string(EUROC_TO_BAG_BIN) + " " + asl + " " + temp.path() + "/out.bag",
       no_images_listed},
      {std::string(EVALUATE_PLACE_RECOGNITION_BIN) + " " + asl, no_images_listed},
      {std::string(EVALUATE_PLACE_RECOGNITION_BIN) + " " + folder + " --gt " + poses,
       "empty_folder: no images"},
      {std::string(EVALUATE_PNP_BIN) + " " + asl + out, no_images_listed},
      {std::string(EVALUATE_RELOCALIZATION_BIN) + " " + asl + " --quiet", no_images_listed},
      {std::string(BENCHMARK_RELOCALIZATION_BIN) + " " + asl, no_images_listed},
      {std::string(FABMAP_MATCH_BIN) + " " + asl, no_images_listed},
      {std::string(TRAIN_FABMAP_BIN) + out + " " + folder, "empty_folder: no images"},
      {std::string(TRAIN_FABMAP_BIN) + out + " " + asl, no_images_listed},
      {std::string(EVALUATE_TRAJECTORY_BIN) + " --gt " + poses + " --est " + poses,
       "poses.txt: no poses in file"},
  };
  for (const auto& [command, message] : runs) {
    std::string output;
    EXPECT_EQ(RunCommand(command + " 2>&1", &output), 1) << command << ": " << output;
    EXPECT_NE(output.find(message), std::string::npos) << command << ": " << output;
  }
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
