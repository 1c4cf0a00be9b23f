#pragma once

#include <string>

#include "stereo_fabmap_slam/io/trajectory.h"

namespace stereo_fabmap_slam::io {

enum class TrajectoryFormat {
  kTum,    // "t x y z qx qy qz qw[ more]", t in seconds, whitespace separated
  kEuroc,  // "t_ns, x, y, z, qw, qx, qy, qz[, more]" (EuRoC ground truth CSV)
  kKitti,  // 12 numbers a line, the top 3x4 of T_world_camera, no timestamps
};

// What a file held that other tools write and this reader accepts, for the caller to warn of:
// stamps equal to the previous one, stamps earlier than the previous one (both kept, in file
// order, as evo keeps them), and a header row without '#' (skipped).
struct TrajectoryFileNotes {
  std::size_t repeated_stamps = 0;
  std::size_t unordered_stamps = 0;
  bool header_skipped = false;
};

// The readers accept what evo accepts: '#' comment lines and blank lines anywhere, \r\n line
// ends, numbers with exponents (timestamps too), columns beyond the pose (ignored), a header row
// first, repeated and unordered timestamps (`notes` counts them). Quaternions are normalised.
// Each throws io::InputError naming the file and line of the first entry that cannot be meant:
// a field that is not a number, NaN or infinity, a quaternion of zero length, too few fields.
Trajectory ReadTumTrajectory(const std::string& path, TrajectoryFileNotes* notes = nullptr);
Trajectory ReadEurocTrajectory(const std::string& path, TrajectoryFileNotes* notes = nullptr);
Trajectory ReadKittiTrajectory(const std::string& path);

// Writers throw io::InputError if the file cannot be written.
void WriteTumTrajectory(const Trajectory& trajectory, const std::string& path);
void WriteEurocTrajectory(const Trajectory& trajectory, const std::string& path);
void WriteKittiTrajectory(const Trajectory& trajectory, const std::string& path);

// Guesses the format: ".csv" or commas mean EuRoC, 12 fields a line KITTI, 8 or more TUM.
TrajectoryFormat DetectTrajectoryFormat(const std::string& path);
Trajectory ReadTrajectory(const std::string& path, TrajectoryFormat format,
                          TrajectoryFileNotes* notes = nullptr);
// The detected format.
Trajectory ReadTrajectory(const std::string& path, TrajectoryFileNotes* notes = nullptr);

}  // namespace stereo_fabmap_slam::io
