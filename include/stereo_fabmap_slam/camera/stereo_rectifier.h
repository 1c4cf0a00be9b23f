#pragma once

#include <vector>

#include <Eigen/Geometry>
#include <opencv2/core.hpp>

#include "stereo_fabmap_slam/camera/camera_calibration.h"
#include "stereo_fabmap_slam/camera/camera_options.h"
#include "stereo_fabmap_slam/concurrency/helper_thread.h"
#include "stereo_fabmap_slam/geometry/stereo_camera.h"
#include "stereo_fabmap_slam/io/option_reader.h"

namespace stereo_fabmap_slam::camera {

// How one raw camera is rectified, in the terms of a ROS CameraInfo: raw intrinsics K and
// distortion D, the rectifying rotation R (p_rectified = R p_raw) and the rectified projection P.
struct RectificationParameters {
  cv::Size size;
  cv::Matx33d K;
  std::vector<double> D;  // k1 k2 p1 p2 [k3]
  cv::Matx33d R;
  cv::Matx34d P;
};

// Turns raw stereo images into a rectified pair described by a StereoCamera. Built once, then
// Rectify() is a pair of cv::remap calls with precomputed fixed-point maps.
class StereoRectifier {
 public:
  // From two calibrated cameras (EuRoC sensor.yaml, config/euroc_stereo.yaml).
  static StereoRectifier FromCalibration(const StereoCalibration& calibration,
                                         const RectificationOptions& options = {});
  // From ready-made rectification parameters (e.g. a pair of CameraInfo messages) and the pose of
  // the raw left camera in the body frame. Throws std::invalid_argument if the pair is not a
  // horizontal rectified stereo pair.
  static StereoRectifier FromParameters(const RectificationParameters& left,
                                        const RectificationParameters& right,
                                        const Eigen::Isometry3d& T_body_left_raw);

  // Raw mono8 images of the calibrated size in, rectified mono8 images out.
  // Throws std::invalid_argument on a wrong size or type. With a helper, bands of rows of both
  // images are remapped on it and the calling thread (the same pixels as without).
  void Rectify(const cv::Mat& left_raw, const cv::Mat& right_raw, cv::Mat* left, cv::Mat* right,
               concurrency::HelperThread* helper = nullptr) const;

  const geometry::StereoCamera& camera() const { return camera_; }
  const RectificationParameters& left_parameters() const { return left_; }
  const RectificationParameters& right_parameters() const { return right_; }
  // Pose of the rectified left camera in the body frame (T_BS of the camera that odometry tracks).
  const Eigen::Isometry3d& T_body_rectified_left() const { return T_body_rectified_left_; }

 private:
  StereoRectifier() = default;

  RectificationParameters left_, right_;
  geometry::StereoCamera camera_;
  Eigen::Isometry3d T_body_rectified_left_ = Eigen::Isometry3d::Identity();
  cv::Mat left_map1_, left_map2_, right_map1_, right_map2_;
};

}  // namespace stereo_fabmap_slam::camera
