#include "stereo_fabmap_slam/geometry/pose_parameters.h"

namespace stereo_fabmap_slam::geometry {

PoseParameters PoseParameters::FromTransform(const Eigen::Isometry3d& T_camera_world) {
  PoseParameters parameters;
  const Eigen::Quaterniond q(T_camera_world.linear());
  Eigen::Map<Eigen::Quaterniond>(parameters.rotation) = q.normalized();
  Eigen::Map<Eigen::Vector3d>(parameters.translation) = T_camera_world.translation();
  return parameters;
}

Eigen::Isometry3d PoseParameters::ToTransform() const {
  Eigen::Isometry3d transform = Eigen::Isometry3d::Identity();
  transform.linear() =
      Eigen::Map<const Eigen::Quaterniond>(rotation).normalized().toRotationMatrix();
  transform.translation() = Eigen::Map<const Eigen::Vector3d>(translation);
  return transform;
}

}  // namespace stereo_fabmap_slam::geometry
