#pragma once

#include <optional>
#include <string>

#include "stereo_fabmap_slam/io/option_reader.h"

namespace stereo_fabmap_slam::pipeline {

// Mapping extends the map with every keyframe; localization tracks against a map (loaded from a
// file) without changing it: the odometry runs as always, and relocalizations against the map
// (at start, after every loss, and at each of the odometry's keyframes) give map -> odom.
enum class SlamMode { kMapping, kLocalization };
inline constexpr io::EnumName<SlamMode> kSlamModeNames[] = {
    {SlamMode::kMapping, "mapping"}, {SlamMode::kLocalization, "localization"}};

// The mode a name means ("mapping", "localization"); nullopt for any other name.
std::optional<SlamMode> ParseSlamMode(const std::string& name);
const char* SlamModeName(SlamMode mode);

}  // namespace stereo_fabmap_slam::pipeline
