#pragma once

#include <string>

#include "stereo_fabmap_slam/evaluation/trajectory.h"

namespace stereo_fabmap_slam::evaluation {

enum class TrajectoryFormat {
  kTum,    // "t x y z qx qy qz qw", t in seconds, whitespace separated
  kEuroc,  // "t_ns, x, y, z, qw, qx, qy, qz[, 9 more columns]" (EuRoC ground truth CSV)
  kKitti,  // 12 numbers a line, the top 3x4 of T_world_camera, no timestamps
};

// Each reader throws io::InputError naming the file and line of the first malformed entry.
Trajectory ReadTumTrajectory(const std::string& path);
Trajectory ReadEurocTrajectory(const std::string& path);
Trajectory ReadKittiTrajectory(const std::string& path);

// Writers throw io::InputError if the file cannot be written.
void WriteTumTrajectory(const Trajectory& trajectory, const std::string& path);
void WriteEurocTrajectory(const Trajectory& trajectory, const std::string& path);
void WriteKittiTrajectory(const Trajectory& trajectory, const std::string& path);

// Guesses the format: ".csv" or commas mean EuRoC, 12 fields a line KITTI, 8 fields TUM.
TrajectoryFormat DetectTrajectoryFormat(const std::string& path);
Trajectory ReadTrajectory(const std::string& path, TrajectoryFormat format);
Trajectory ReadTrajectory(const std::string& path);  // detected format

}  // namespace stereo_fabmap_slam::evaluation
