#include "stereo_fabmap_slam/geometry/pose_covariance.h"

namespace stereo_fabmap_slam::geometry {
Eigen::Matrix<double, 6, 6> Adjoint(const Eigen::Isometry3d& T) {
  Eigen::Matrix<double, 6, 6> adjoint = Eigen::Matrix<double, 6, 6>::Zero();
  const Eigen::Matrix3d R = T.rotation();
  adjoint.topLeftCorner<3, 3>() = R;
  adjoint.topRightCorner<3, 3>() = Skew(T.translation()) * R;
  adjoint.bottomRightCorner<3, 3>() = R;
  return adjoint;
}

Eigen::Matrix3d StereoProjectionJacobian(const StereoCamera& camera, const Eigen::Vector3d& p) {
  const double inverse_z = 1.0 / p.z();
  Eigen::Matrix3d projection;
  projection << camera.fx * inverse_z, 0, -camera.fx * p.x() * inverse_z * inverse_z,  //
      0, camera.fy * inverse_z, -camera.fy * p.y() * inverse_z * inverse_z,            //
      camera.fx * inverse_z, 0, -camera.fx * (p.x() - camera.baseline) * inverse_z * inverse_z;
  return projection;
}

PoseCovariance StereoPoseCovariance(const StereoCamera& camera,
                                    const std::vector<ObservedPoint>& points, double pixel_sigma) {
  Eigen::Matrix<double, 6, 6> information = Eigen::Matrix<double, 6, 6>::Zero();
  int used = 0;
  for (const ObservedPoint& point : points) {
    const Eigen::Vector3d& p = point.camera;
    if (p.z() <= 0) continue;
    const Eigen::Matrix3d projection = StereoProjectionJacobian(camera, p);
    // The point in the perturbed camera T * Exp(delta) is Exp(-delta) * p: dp/dtranslation =
    // -I, dp/drotation = [p]x.
    Eigen::Matrix<double, 3, 6> point_jacobian;
    point_jacobian.leftCols<3>() = -Eigen::Matrix3d::Identity();
    point_jacobian.rightCols<3>() = Skew(p);
    const Eigen::Matrix<double, 3, 6> jacobian = projection * point_jacobian;
    const int rows = point.stereo ? 3 : 2;
    information += jacobian.topRows(rows).transpose() * jacobian.topRows(rows);
    ++used;
  }
  constexpr double kUnknown = 1e6;  // [m^2], [rad^2]: "not estimated"
  if (used < 3) return PoseCovariance::Identity() * kUnknown;
  const Eigen::LDLT<Eigen::Matrix<double, 6, 6>> decomposition(information);
  // An information matrix whose smallest pivot is 1e-12 of its largest leaves a direction the
  // points do not constrain (e.g. all points on one ray); its inverse would be noise.
  const Eigen::VectorXd pivots = decomposition.vectorD().cwiseAbs();
  if (decomposition.info() != Eigen::Success || pivots.minCoeff() <= 1e-12 * pivots.maxCoeff()) {
    return PoseCovariance::Identity() * kUnknown;
  }
  const PoseCovariance covariance =
      decomposition.solve(Eigen::Matrix<double, 6, 6>::Identity()) * (pixel_sigma * pixel_sigma);
  return 0.5 * (covariance + covariance.transpose());
}

PoseCovariance MoveCovarianceToFrame(const PoseCovariance& covariance, const Eigen::Isometry3d& B) {
  // T * B * Exp(delta') = T * Exp(delta) * B  =>  delta' = Ad(B^-1) * delta.
  const Eigen::Matrix<double, 6, 6> adjoint = Adjoint(B.inverse());
  return adjoint * covariance * adjoint.transpose();
}

PoseCovariance RotateCovariance(const PoseCovariance& covariance, const Eigen::Matrix3d& R) {
  Eigen::Matrix<double, 6, 6> rotation = Eigen::Matrix<double, 6, 6>::Zero();
  rotation.topLeftCorner<3, 3>() = R;
  rotation.bottomRightCorner<3, 3>() = R;
  return rotation * covariance * rotation.transpose();
}

}  // namespace stereo_fabmap_slam::geometry
