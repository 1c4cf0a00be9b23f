#pragma once

#include <Eigen/Geometry>

namespace stereo_fabmap_slam::geometry {

// T_camera_world as Ceres parameter blocks: an Eigen quaternion (x, y, z, w) and a translation.
struct PoseParameters {
  double rotation[4];
  double translation[3];

  static PoseParameters FromTransform(const Eigen::Isometry3d& T_camera_world);
  Eigen::Isometry3d ToTransform() const;
};

}  // namespace stereo_fabmap_slam::geometry
