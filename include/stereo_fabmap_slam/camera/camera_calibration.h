#pragma once

#include <string>
#include <vector>

#include <Eigen/Geometry>
#include <opencv2/core.hpp>

#include "stereo_fabmap_slam/io/yaml_file.h"

namespace stereo_fabmap_slam::camera {

// Intrinsics and extrinsics of one raw (distorted, unrectified) pinhole camera, as EuRoC's
// sensor.yaml describes it. Distortion is radial-tangential (OpenCV's plumb_bob): k1 k2 p1 p2 [k3].
struct CameraCalibration {
  cv::Size resolution;
  double fx = 0, fy = 0, cx = 0, cy = 0;
  std::vector<double> distortion;                                   // k1 k2 p1 p2 [k3]
  Eigen::Isometry3d T_body_camera = Eigen::Isometry3d::Identity();  // T_BS
  double rate_hz = 0;                                               // 0 if not given

  cv::Matx33d CameraMatrix() const;
  // Throws std::invalid_argument naming the first bad value.
  void Validate() const;
};

struct StereoCalibration {
  CameraCalibration left;
  CameraCalibration right;
  // The robot's base frame (REP-103: x forward, y left, z up) in the body frame T_BS refers to,
  // for ROS's base_link; optional (identity: the body is the base). EuRoC's body is its IMU,
  // x up and z forward, so its file gives the rotation to a level base at the IMU.
  Eigen::Isometry3d T_body_base = Eigen::Isometry3d::Identity();

  // Transform taking points from the left camera frame to the right camera frame.
  Eigen::Isometry3d T_right_left() const;
  void Validate() const;
};

// Parses one camera in EuRoC sensor.yaml form from `node` of `file`: resolution, intrinsics,
// distortion_model (radial-tangential), distortion_coefficients, T_BS (either {rows, cols, data}
// or a flat list of 16 numbers), optional rate_hz. Throws io::InputError with file and line.
CameraCalibration ParseCameraCalibration(const io::YamlFile& file, const YAML::Node& node);

// Reads an EuRoC sensor.yaml (with or without the "%YAML:1.0" line).
CameraCalibration ReadEurocSensorYaml(const std::string& path);

// Reads a stereo calibration file with "left:" and "right:" camera sections in sensor.yaml form
// (config/euroc_stereo.yaml).
StereoCalibration ReadStereoCalibrationYaml(const std::string& path);

// Writers of the same two formats (15 significant digits); throw std::runtime_error on failure.
void WriteEurocSensorYaml(const CameraCalibration& camera, const std::string& comment,
                          const std::string& path);
void WriteStereoCalibrationYaml(const StereoCalibration& calibration, const std::string& path);

}  // namespace stereo_fabmap_slam::camera
