#pragma once

#include <ceres/ceres.h>
#include <Eigen/Geometry>

#include "stereo_fabmap_slam/geometry/stereo_camera.h"

namespace stereo_fabmap_slam::geometry {

// Reprojection error of a world point in a rectified stereo camera, in units of the pixel noise
// sigma: (u_left, v) and, for a stereo observation, u_right. Parameter blocks: the rotation of
// T_camera_world as an Eigen quaternion (x, y, z, w), its translation, and the point.
class ReprojectionError {
 public:
  // u_right < 0: a mono observation; otherwise stereo. What Ceres solves with is ReprojectionCost
  // below, this functor's expression with Jacobians derived by hand. This makes Ceres' automatic
  // derivatives of the functor (2 residuals for a mono observation, 3 for a stereo one): the
  // reference the hand-derived Jacobians are tested against.
  static ceres::CostFunction* CreateAutoDiff(const geometry::StereoCamera& camera, double u,
                                             double v, double u_right, double sigma);

  ReprojectionError(const geometry::StereoCamera& camera, double u, double v, double u_right,
                    double sigma)
      : fx_(camera.fx),
        fy_(camera.fy),
        cx_(camera.cx),
        cy_(camera.cy),
        fx_baseline_(camera.fx * camera.baseline),
        u_(u),
        v_(v),
        u_right_(u_right),
        inverse_sigma_(1.0 / sigma) {}

  template <typename T>
  bool operator()(const T* rotation, const T* translation, const T* point, T* residuals) const {
    const Eigen::Map<const Eigen::Quaternion<T>> q(rotation);
    const Eigen::Map<const Eigen::Matrix<T, 3, 1>> t(translation);
    const Eigen::Map<const Eigen::Matrix<T, 3, 1>> p(point);
    const Eigen::Matrix<T, 3, 1> c = q * p + t;
    const T inverse_z = T(1.0) / c.z();
    const T u = T(fx_) * c.x() * inverse_z + T(cx_);
    residuals[0] = (u - T(u_)) * T(inverse_sigma_);
    residuals[1] = (T(fy_) * c.y() * inverse_z + T(cy_) - T(v_)) * T(inverse_sigma_);
    if (u_right_ >= 0) {
      residuals[2] = (u - T(fx_baseline_) * inverse_z - T(u_right_)) * T(inverse_sigma_);
    }
    return true;
  }

 private:
  double fx_, fy_, cx_, cy_, fx_baseline_;
  double u_, v_, u_right_, inverse_sigma_;
};

// One observation's constants in the reprojection error: the rectified camera and what was
// measured (u_right < 0: mono), as the costs below keep them.
struct ProjectionConstants {
  double fx = 0, fy = 0, cx = 0, cy = 0, fx_baseline = 0;
  double u = 0, v = 0, u_right = -1, inverse_sigma = 1;

  static ProjectionConstants Of(const geometry::StereoCamera& camera, double u, double v,
                                double u_right, double sigma);
};

// ReprojectionError's expression with Jacobians derived by hand, and 3 residuals for either kind
// of observation (a mono observation's third is 0, so that Ceres' Schur elimination sees one row
// size). The observation can be set again: a bundle adjustment keeps one array of them from
// solve to solve instead of allocating one per residual and solve (two allocations each, ~8,000
// a keyframe).
class ReprojectionCost final : public ceres::SizedCostFunction<3, 4, 3, 3> {
 public:
  void Set(const geometry::StereoCamera& camera, double u, double v, double u_right, double sigma);
  bool Evaluate(double const* const* parameters, double* residuals,
                double** jacobians) const override;

 private:
  ProjectionConstants constants_;
};

// The same error for a point held fixed (motion-only optimisation): the point is part of the
// cost function, so the problem has only the two pose blocks. Settable again, as ReprojectionCost:
// a pose refinement allocates one array of them for its rounds, not one cost per residual and
// round.
class FixedPointReprojectionCost final : public ceres::SizedCostFunction<3, 4, 3> {
 public:
  void Set(const geometry::StereoCamera& camera, const Eigen::Vector3d& point, double u, double v,
           double u_right, double sigma);
  bool Evaluate(double const* const* parameters, double* residuals,
                double** jacobians) const override;

 private:
  ProjectionConstants constants_;
  Eigen::Vector3d point_ = Eigen::Vector3d::Zero();
};

// Squared error in units of sigma^2 of an observation at a pose, and whether it has 3 residuals;
// for chi-square outlier tests outside Ceres. A point behind the camera gives infinity.
double SquaredReprojectionError(const geometry::StereoCamera& camera,
                                const Eigen::Isometry3d& T_camera_world,
                                const Eigen::Vector3d& point, double u, double v, double u_right,
                                double sigma);

}  // namespace stereo_fabmap_slam::geometry
