#pragma once

// For rostests that play a EuRoC subset: the subset written into a bag by euroc_to_bag (whose
// path the test's CMake target defines as EUROC_TO_BAG_BIN).

#include <string>

#include <gtest/gtest.h>

#include "test_support.h"

namespace stereo_fabmap_slam::test {

// Writes ../shared/data/euroc/<name> into `bag`; a failure fails the test with the tool's output.
inline void WriteEurocSubsetBag(const std::string& name, const std::string& bag) {
  std::string output;
  ASSERT_EQ(RunCommand(
                std::string(EUROC_TO_BAG_BIN) + " " + EurocSequencePath(name) + " " + bag + " 2>&1",
                &output),
            0)
      << output;
}

}  // namespace stereo_fabmap_slam::test
