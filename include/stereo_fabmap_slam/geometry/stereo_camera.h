#pragma once

#include <Eigen/Core>
#include <opencv2/core.hpp>

namespace stereo_fabmap_slam::geometry {

// A rectified stereo pair: two identical pinhole cameras, the right one `baseline` metres along
// the left camera's x axis, so that a 3-D point appears on the same image row in both.
struct StereoCamera {
  cv::Size size;
  double fx = 0, fy = 0, cx = 0, cy = 0;
  double baseline = 0;  // [m]

  // Point in the left camera frame seen at (u_left, v) with disparity u_left - u_right > 0.
  Eigen::Vector3d Triangulate(double u_left, double v, double disparity) const;
  // (u_left, v, u_right) of a point in the left camera frame; the point must have z > 0.
  Eigen::Vector3d Project(const Eigen::Vector3d& point_left) const;
  double DepthFromDisparity(double disparity) const { return fx * baseline / disparity; }
  cv::Matx33d CameraMatrix() const { return cv::Matx33d(fx, 0, cx, 0, fy, cy, 0, 0, 1); }
};

}  // namespace stereo_fabmap_slam::geometry
