#pragma once

#include <cmath>

#include <ceres/autodiff_cost_function.h>
#include <Eigen/Core>
#include <Eigen/Geometry>

namespace stereo_fabmap_slam::geometry {

// Information (inverse covariance) of a relative pose with independent errors of
// `translation_sigma` [m] per axis and `rotation_sigma_deg` per axis, in RelativePoseError's
// order (translation, rotation).
inline Eigen::Matrix<double, 6, 6> DiagonalPoseInformation(double translation_sigma,
                                                           double rotation_sigma_deg) {
  const double rotation_sigma = rotation_sigma_deg * (M_PI / 180.0);
  Eigen::Matrix<double, 6, 1> diagonal;
  diagonal.head<3>().setConstant(1.0 / (translation_sigma * translation_sigma));
  diagonal.tail<3>().setConstant(1.0 / (rotation_sigma * rotation_sigma));
  return diagonal.asDiagonal();
}

// Error of a measured relative pose T_a_b between two poses T_world_a and T_world_b, for a pose
// graph. Parameter blocks: the rotation of T_world_a as an Eigen quaternion (x, y, z, w), its
// translation, then the same two for T_world_b.
//
// The error is the estimated camera b seen from where the measurement puts it,
//   T_err = T_a_b_measured^-1 * T_world_a^-1 * T_world_b,
// as (translation of T_err, 2 * vec(q_err)): both parts in the measured b frame, so one 6x6
// information matrix describes the relative pose's uncertainty consistently. 2 * vec(q) is the
// rotation vector to second order in the angle and needs no trigonometry; it saturates near
// 180 degrees, which only ever concerns a grossly wrong edge. The residual is the error times the
// square-root information (upper Cholesky factor), so its squared norm is the Mahalanobis
// distance and a robust loss can be scaled in standard deviations.
class RelativePoseError {
 public:
  // sqrt_information: any S with S^T * S = information, e.g. the transposed lower Cholesky factor
  // (Ceres' example uses the lower factor itself, which is only right for diagonal matrices).
  static ceres::CostFunction* Create(const Eigen::Isometry3d& T_a_b_measured,
                                     const Eigen::Matrix<double, 6, 6>& sqrt_information) {
    return new ceres::AutoDiffCostFunction<RelativePoseError, 6, 4, 3, 4, 3>(
        new RelativePoseError(T_a_b_measured, sqrt_information));
  }

  RelativePoseError(const Eigen::Isometry3d& T_a_b_measured,
                    const Eigen::Matrix<double, 6, 6>& sqrt_information)
      // Stored inverted: the residual needs T_b_a_measured, and inverting once here saves a
      // conjugate per evaluation.
      : q_b_a_measured_(Eigen::Quaterniond(T_a_b_measured.rotation()).conjugate()),
        t_a_b_measured_(T_a_b_measured.translation()),
        sqrt_information_(sqrt_information) {}

  template <typename T>
  bool operator()(const T* rotation_a, const T* translation_a, const T* rotation_b,
                  const T* translation_b, T* residuals) const {
    const Eigen::Map<const Eigen::Quaternion<T>> q_world_a(rotation_a);
    const Eigen::Map<const Eigen::Matrix<T, 3, 1>> t_world_a(translation_a);
    const Eigen::Map<const Eigen::Quaternion<T>> q_world_b(rotation_b);
    const Eigen::Map<const Eigen::Matrix<T, 3, 1>> t_world_b(translation_b);

    const Eigen::Quaternion<T> q_a_world = q_world_a.conjugate();
    const Eigen::Quaternion<T> q_a_b = q_a_world * q_world_b;
    const Eigen::Matrix<T, 3, 1> t_a_b = q_a_world * (t_world_b - t_world_a);

    const Eigen::Quaternion<T> q_b_a_measured = q_b_a_measured_.template cast<T>();
    Eigen::Matrix<T, 6, 1> error;
    error.template head<3>() = q_b_a_measured * (t_a_b - t_a_b_measured_.template cast<T>());
    error.template tail<3>() = T(2.0) * (q_b_a_measured * q_a_b).vec();

    Eigen::Map<Eigen::Matrix<T, 6, 1>> residual(residuals);
    residual = sqrt_information_.template cast<T>() * error;
    return true;
  }

 private:
  Eigen::Quaterniond q_b_a_measured_;
  Eigen::Vector3d t_a_b_measured_;
  Eigen::Matrix<double, 6, 6> sqrt_information_;
};

}  // namespace stereo_fabmap_slam::geometry
