#include "stereo_fabmap_slam/io/trajectory.h"

namespace stereo_fabmap_slam::io {

Eigen::Isometry3d PoseFromTranslationQuaternion(const Eigen::Vector3d& translation,
                                                const Eigen::Quaterniond& rotation) {
  Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
  pose.linear() = rotation.normalized().toRotationMatrix();
  pose.translation() = translation;
  return pose;
}

}  // namespace stereo_fabmap_slam::io
