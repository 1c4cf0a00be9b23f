#include "stereo_fabmap_slam/pipeline/slam_mode.h"

namespace stereo_fabmap_slam::pipeline {

std::optional<SlamMode> ParseSlamMode(const std::string& name) {
  for (const auto& entry : kSlamModeNames) {
    if (name == entry.name) return entry.value;
  }
  return std::nullopt;
}

const char* SlamModeName(SlamMode mode) {
  for (const auto& entry : kSlamModeNames) {
    if (mode == entry.value) return entry.name;
  }
  return "?";
}

}  // namespace stereo_fabmap_slam::pipeline
