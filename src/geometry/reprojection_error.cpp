#include "stereo_fabmap_slam/geometry/reprojection_error.h"

#include <limits>

#include "stereo_fabmap_slam/geometry/pose_covariance.h"

namespace stereo_fabmap_slam::geometry {

namespace {

// The residual of ReprojectionError and its Jacobians, by hand: Ceres' automatic derivatives of
// the same expression cost a dual number of 10 (or 7) components per operation, and bundle
// adjustment and pose refinement spend most of their time evaluating these residuals. The
// expression is the functor's, term for term (Eigen's rotation of a vector by a quaternion,
// p + w * uv + vec x uv with uv = 2 vec x p), so the Jacobians are those of the functor even for a
// quaternion a step has taken slightly off the unit sphere.
// Three residuals always, the third 0 with a zero Jacobian row for a mono observation: with
// one row size for every observation Ceres' Schur elimination runs its code specialised for
// 3 residuals, 3-d points and 3-d pose blocks instead of its generic one (bundle adjustment
// 62 -> 50 ms a keyframe on the rendered 4-lap loop; the solution is the same, the zero row
// adds nothing to the cost or the normal equations).
// Jacobians (Ceres' layout: row-major, 3 x block size); any may be null.
void EvaluateProjection(const ProjectionConstants& constants, const double* rotation,
                        const double* translation, const double* point, double* residuals,
                        double* d_rotation, double* d_translation, double* d_point) {
  const auto& [fx, fy, cx, cy, fx_baseline, u, v, u_right, inverse_sigma] = constants;
  const Eigen::Map<const Eigen::Vector3d> vec(rotation);  // x, y, z; w follows
  const double w = rotation[3];
  const Eigen::Map<const Eigen::Vector3d> t(translation);
  const Eigen::Map<const Eigen::Vector3d> p(point);
  const Eigen::Vector3d uv = 2.0 * vec.cross(p);
  const Eigen::Vector3d c = p + w * uv + vec.cross(uv) + t;
  const double inverse_z = 1.0 / c.z();
  const double projected_u = fx * c.x() * inverse_z + cx;
  residuals[0] = (projected_u - u) * inverse_sigma;
  residuals[1] = (fy * c.y() * inverse_z + cy - v) * inverse_sigma;
  const bool stereo = u_right >= 0;
  residuals[2] = stereo ? (projected_u - fx_baseline * inverse_z - u_right) * inverse_sigma : 0.0;
  if (d_rotation == nullptr && d_translation == nullptr && d_point == nullptr) return;

  // d residual / d c, the point in the camera.
  Eigen::Matrix3d d_c;
  const double inverse_z2 = inverse_z * inverse_z;
  d_c.row(0) << fx * inverse_z, 0.0, -fx * c.x() * inverse_z2;
  d_c.row(1) << 0.0, fy * inverse_z, -fy * c.y() * inverse_z2;
  if (stereo) {
    d_c.row(2) << fx * inverse_z, 0.0, (fx_baseline - fx * c.x()) * inverse_z2;
  } else {
    d_c.row(2).setZero();
  }
  d_c *= inverse_sigma;
  using Block3 = Eigen::Matrix<double, 3, 3, Eigen::RowMajor>;
  if (d_translation != nullptr) {
    Eigen::Map<Block3> jacobian(d_translation);
    jacobian = d_c;
  }
  if (d_point == nullptr && d_rotation == nullptr) return;
  const Eigen::Matrix3d vec_hat = Skew(vec);
  if (d_point != nullptr) {
    // d c / d p = I + 2 w [vec]x + 2 [vec]x [vec]x: the rotation matrix of a unit quaternion.
    Eigen::Map<Block3> jacobian(d_point);
    jacobian = d_c * (Eigen::Matrix3d::Identity() + 2.0 * w * vec_hat + 2.0 * vec_hat * vec_hat);
  }
  if (d_rotation != nullptr) {
    // d c / d vec = -2 w [p]x - 2 [vec]x [p]x - [uv]x; d c / d w = uv.
    const Eigen::Matrix3d p_hat = Skew(p);
    Eigen::Matrix<double, 3, 4> d_c_d_q;
    d_c_d_q.leftCols<3>() = -2.0 * w * p_hat - 2.0 * vec_hat * p_hat - Skew(uv);
    d_c_d_q.col(3) = uv;
    Eigen::Map<Eigen::Matrix<double, 3, 4, Eigen::RowMajor>> jacobian(d_rotation);
    jacobian = d_c * d_c_d_q;
  }
}

}  // namespace

ProjectionConstants ProjectionConstants::Of(const StereoCamera& camera, double u, double v,
                                            double u_right, double sigma) {
  return {camera.fx, camera.fy, camera.cx, camera.cy,  camera.fx * camera.baseline,
          u,         v,         u_right,   1.0 / sigma};
}

void ReprojectionCost::Set(const StereoCamera& camera, double u, double v, double u_right,
                           double sigma) {
  constants_ = ProjectionConstants::Of(camera, u, v, u_right, sigma);
}

bool ReprojectionCost::Evaluate(double const* const* parameters, double* residuals,
                                double** jacobians) const {
  EvaluateProjection(constants_, parameters[0], parameters[1], parameters[2], residuals,
                     jacobians != nullptr ? jacobians[0] : nullptr,
                     jacobians != nullptr ? jacobians[1] : nullptr,
                     jacobians != nullptr ? jacobians[2] : nullptr);
  return true;
}

void FixedPointReprojectionCost::Set(const StereoCamera& camera, const Eigen::Vector3d& point,
                                     double u, double v, double u_right, double sigma) {
  constants_ = ProjectionConstants::Of(camera, u, v, u_right, sigma);
  point_ = point;
}

bool FixedPointReprojectionCost::Evaluate(double const* const* parameters, double* residuals,
                                          double** jacobians) const {
  EvaluateProjection(constants_, parameters[0], parameters[1], point_.data(), residuals,
                     jacobians != nullptr ? jacobians[0] : nullptr,
                     jacobians != nullptr ? jacobians[1] : nullptr, nullptr);
  return true;
}

ceres::CostFunction* ReprojectionError::CreateAutoDiff(const geometry::StereoCamera& camera,
                                                       double u, double v, double u_right,
                                                       double sigma) {
  if (u_right >= 0) {
    return new ceres::AutoDiffCostFunction<ReprojectionError, 3, 4, 3, 3>(
        new ReprojectionError(camera, u, v, u_right, sigma));
  }
  return new ceres::AutoDiffCostFunction<ReprojectionError, 2, 4, 3, 3>(
      new ReprojectionError(camera, u, v, u_right, sigma));
}

double SquaredReprojectionError(const geometry::StereoCamera& camera,
                                const Eigen::Isometry3d& T_camera_world,
                                const Eigen::Vector3d& point, double u, double v, double u_right,
                                double sigma) {
  const Eigen::Vector3d c = T_camera_world * point;
  if (c.z() <= 1e-6) return std::numeric_limits<double>::infinity();
  const Eigen::Vector3d projected = camera.Project(c);
  double squared =
      (projected.x() - u) * (projected.x() - u) + (projected.y() - v) * (projected.y() - v);
  if (u_right >= 0) squared += (projected.z() - u_right) * (projected.z() - u_right);
  return squared / (sigma * sigma);
}

}  // namespace stereo_fabmap_slam::geometry
