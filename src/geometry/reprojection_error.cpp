#include "stereo_fabmap_slam/geometry/reprojection_error.h"

#include <limits>

namespace stereo_fabmap_slam::geometry {

ceres::CostFunction* ReprojectionError::Create(const geometry::StereoCamera& camera, double u,
                                               double v, double u_right, double sigma) {
  if (u_right >= 0) {
    return new ceres::AutoDiffCostFunction<ReprojectionError, 3, 4, 3, 3>(
        new ReprojectionError(camera, u, v, u_right, sigma));
  }
  return new ceres::AutoDiffCostFunction<ReprojectionError, 2, 4, 3, 3>(
      new ReprojectionError(camera, u, v, u_right, sigma));
}

ceres::CostFunction* FixedPointReprojectionError::Create(const geometry::StereoCamera& camera,
                                                         const Eigen::Vector3d& point, double u,
                                                         double v, double u_right, double sigma) {
  if (u_right >= 0) {
    return new ceres::AutoDiffCostFunction<FixedPointReprojectionError, 3, 4, 3>(
        new FixedPointReprojectionError(camera, point, u, v, u_right, sigma));
  }
  return new ceres::AutoDiffCostFunction<FixedPointReprojectionError, 2, 4, 3>(
      new FixedPointReprojectionError(camera, point, u, v, u_right, sigma));
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
