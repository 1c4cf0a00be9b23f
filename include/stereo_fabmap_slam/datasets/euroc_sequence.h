#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include <opencv2/core.hpp>

#include "stereo_fabmap_slam/camera/camera_calibration.h"
#include "stereo_fabmap_slam/io/trajectory.h"

namespace stereo_fabmap_slam::datasets {

struct EurocSequenceOptions {
  // Left and right images pair when their stamps differ by at most this much.
  std::int64_t max_pair_dt_ns = 1'000'000;
};

struct StereoFrameEntry {
  std::int64_t timestamp_ns = 0;  // the left image's stamp
  std::string left_path;
  std::string right_path;
};

struct UnpairedImage {
  std::string camera;  // "cam0" or "cam1"
  std::int64_t timestamp_ns = 0;
  std::string path;
};

struct StereoImages {
  std::int64_t timestamp_ns = 0;
  cv::Mat left;   // raw mono8
  cv::Mat right;  // raw mono8
};

// A stereo sequence in EuRoC's ASL folder layout (mav0/cam0, mav0/cam1, optional
// mav0/state_groundtruth_estimate0). Opening reads the lists, calibrations and ground truth;
// images are read from disk only when asked for, so long sequences cost no memory.
class EurocSequence {
 public:
  // `directory` is the sequence folder (holding mav0/) or mav0 itself. Throws InputError naming
  // the file (and line) of the first problem: a missing folder or file, a malformed line.
  static EurocSequence Open(const std::string& directory, const EurocSequenceOptions& options = {});

  std::size_t size() const { return frames_.size(); }
  const std::vector<StereoFrameEntry>& frames() const { return frames_; }
  // Images of frame i. Throws InputError naming the file if an image is unreadable or its size
  // differs from the calibration.
  StereoImages LoadStereoPair(std::size_t i) const;

  const camera::StereoCalibration& calibration() const { return calibration_; }
  bool has_ground_truth() const { return !ground_truth_.empty(); }
  // Pose of the body (IMU) frame in the world frame; empty without ground truth.
  const io::Trajectory& ground_truth() const { return ground_truth_; }
  // Images in one camera's list that have no partner in the other's.
  const std::vector<UnpairedImage>& unpaired() const { return unpaired_; }
  const std::string& mav0_directory() const { return mav0_; }

 private:
  EurocSequence() = default;

  std::string mav0_;
  std::vector<StereoFrameEntry> frames_;
  std::vector<UnpairedImage> unpaired_;
  camera::StereoCalibration calibration_;
  io::Trajectory ground_truth_;
};

}  // namespace stereo_fabmap_slam::datasets
