// make test's closing summary (scripts/test_summary.py) on result files made up here: distinct
// cases apart from the sanitizer build's re-runs, a rostest's wrapper case counted only when it
// fails, and a result file CMake expects but no test program wrote (killed, or never run) is a
// failure, not a silence.
#include <filesystem>
#include <string>

#include <gtest/gtest.h>

#include "test_support.h"

namespace stereo_fabmap_slam::test {
namespace {

std::string Suite(const std::string& cases) {
  return "<?xml version=\"1.0\"?>\n<testsuites><testsuite name=\"s\">" + cases +
         "</testsuite></testsuites>\n";
}

const char kPass[] = "<testcase classname=\"A\" name=\"passes\"/>";
const char kFail[] =
    "<testcase classname=\"A\" name=\"fails\"><failure message=\"expected 1\"/></testcase>";

class TestSummary : public ::testing::Test {
 protected:
  void SetUp() override {
    std::filesystem::create_directories(temp_.path() + "/results/stereo_fabmap_slam");
    std::filesystem::create_directories(temp_.path() + "/results/sanitizers");
    Write("stereo_fabmap_slam/gtest-a_test.xml", Suite(std::string(kPass) + kPass));
    Write("stereo_fabmap_slam/rosunit-b.xml", Suite(kPass));
    Write("stereo_fabmap_slam/rostest-test_ros_b.xml", Suite(kPass));  // its wrapper
    Write("sanitizers/sanitize-a_test.xml", Suite(std::string(kPass) + kPass));
    Write("sanitizers/build-sanitize.xml", Suite(kPass));
  }
  void Write(const std::string& name, const std::string& text) {
    WriteTextFile(temp_.path() + "/results/" + name, text);
  }
  // The summary's exit status; `output` receives what it printed.
  int Summarise(const std::string& expected, std::string* output) {
    WriteTextFile(temp_.path() + "/expected.txt", expected);
    return RunCommand("/usr/bin/python3 " + RepositoryRoot() + "/scripts/test_summary.py " +
                          temp_.path() + "/results --expected " + temp_.path() +
                          "/expected.txt 2>&1",
                      output);
  }
  TemporaryDirectory temp_;
};

TEST_F(TestSummary, CountsDistinctCasesApartFromTheSanitizerBuilds) {
  std::string output;
  EXPECT_EQ(Summarise("gtest-a_test.xml\nrostest-test_ros_b.xml\n", &output), 0) << output;
  EXPECT_NE(output.find("tests: 3 passed, 0 failed, 0 skipped"), std::string::npos) << output;
  EXPECT_NE(output.find("sanitizer build: its build and the unit tests again under "
                        "ASan/LSan/UBSan, 3 passed, 0 failed"),
            std::string::npos)
      << output;
}

TEST_F(TestSummary, AMissingResultFileFailsTheRun) {
  std::string output;
  EXPECT_NE(Summarise("gtest-a_test.xml\ngtest-crashed_test.xml\n", &output), 0) << output;
  EXPECT_NE(output.find("FAILED gtest-crashed_test.xml: no result file"), std::string::npos)
      << output;
  EXPECT_NE(output.find("tests: 3 passed, 1 failed"), std::string::npos) << output;
}

TEST_F(TestSummary, AFailedCaseAnywhereFailsTheRun) {
  Write("sanitizers/sanitize-a_test.xml", Suite(std::string(kPass) + kFail));
  std::string output;
  EXPECT_NE(Summarise("gtest-a_test.xml\n", &output), 0) << output;
  EXPECT_NE(output.find("FAILED sanitize-a_test.xml: A.fails: expected 1"), std::string::npos)
      << output;
  EXPECT_NE(output.find("2 passed, 1 failed"), std::string::npos) << "the sanitizer line";
  EXPECT_NE(output.find("tests: 3 passed, 0 failed"), std::string::npos) << output;
}

}  // namespace
}  // namespace stereo_fabmap_slam::test
