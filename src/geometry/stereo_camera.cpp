#include "stereo_fabmap_slam/geometry/stereo_camera.h"

namespace stereo_fabmap_slam::geometry {

Eigen::Vector3d StereoCamera::Triangulate(double u_left, double v, double disparity) const {
  const double z = DepthFromDisparity(disparity);
  return {(u_left - cx) * z / fx, (v - cy) * z / fy, z};
}

Eigen::Vector3d StereoCamera::Project(const Eigen::Vector3d& point_left) const {
  const double inverse_z = 1.0 / point_left.z();
  const double u = fx * point_left.x() * inverse_z + cx;
  const double v = fy * point_left.y() * inverse_z + cy;
  return {u, v, u - fx * baseline * inverse_z};
}

}  // namespace stereo_fabmap_slam::geometry
