#pragma once

#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "stereo_fabmap_slam/geometry/stereo_camera.h"

namespace stereo_fabmap_slam::geometry {

// 6x6 pose covariances, ordered translation xyz then rotation xyz (small-angle vector), of a
// perturbation applied on the right: T' = T * Exp(delta), i.e. expressed in the moving frame.
using PoseCovariance = Eigen::Matrix<double, 6, 6>;

// The cross-product matrix: Skew(a) * b = a x b (inline: the reprojection costs' Jacobians use it
// per residual).
inline Eigen::Matrix3d Skew(const Eigen::Vector3d& a) {
  Eigen::Matrix3d hat;
  hat << 0.0, -a.z(), a.y(), a.z(), 0.0, -a.x(), -a.y(), a.x(), 0.0;
  return hat;
}
// Ad(T) for the (translation, rotation) order: T * Exp(delta) * T^-1 = Exp(Ad(T) * delta), so a
// perturbation in frame b maps to Ad * delta in frame a when T = T_a_b.
Eigen::Matrix<double, 6, 6> Adjoint(const Eigen::Isometry3d& T);
// d(u_left, v, u_right) / d(point in the left camera frame) of the rectified stereo projection;
// the point must have z > 0.
Eigen::Matrix3d StereoProjectionJacobian(const StereoCamera& camera, const Eigen::Vector3d& p);

// One stereo observation of a known point: its position in the camera frame, and whether the
// right image saw it too (three residuals u, v, u_right) or only the left (two).
struct ObservedPoint {
  Eigen::Vector3d camera;
  bool stereo = true;
};

// The Gauss-Newton covariance sigma^2 (J^T J)^-1 of a camera pose estimated from fixed points
// (the motion-only refinement's problem at its optimum), with J the derivative of the pixel
// residuals with respect to the pose perturbation. It says how well the observations pin the
// pose down given the pixel noise; it knows nothing of the points' own errors, so it is a lower
// bound. Fewer than three points, or a degenerate set, give a covariance of 1e6 on the diagonal
// rather than an inverse that does not exist.
PoseCovariance StereoPoseCovariance(const StereoCamera& camera,
                                    const std::vector<ObservedPoint>& points, double pixel_sigma);

// The covariance of T * B for a fixed transform B, given that of T (right perturbations):
// Ad(B^-1) * covariance * Ad(B^-1)^T.
PoseCovariance MoveCovarianceToFrame(const PoseCovariance& covariance, const Eigen::Isometry3d& B);

// The same covariance with its axes rotated into another frame (e.g. from a body frame into the
// odom frame, as nav_msgs/Odometry's pose covariance is given): R * covariance * R^T per block.
PoseCovariance RotateCovariance(const PoseCovariance& covariance, const Eigen::Matrix3d& R);

}  // namespace stereo_fabmap_slam::geometry
