#include "base_frame_convention.h"

namespace stereo_fabmap_slam::ros_conversions {

geometry::PoseCovariance BaseFrameConvention::BaseCovariance(
    const geometry::PoseCovariance& camera_covariance) const {
  // T_odom_base = T_base_camera * T_world_camera * T_camera_base: a fixed transform on the
  // left changes nothing of a right perturbation, the one on the right moves it into the base
  // frame.
  return geometry::MoveCovarianceToFrame(camera_covariance, T_base_camera_.inverse());
}

geometry::PoseCovariance BaseFrameConvention::BaseCovarianceInOdom(
    const Eigen::Isometry3d& T_world_camera,
    const geometry::PoseCovariance& camera_covariance) const {
  return geometry::RotateCovariance(BaseCovariance(camera_covariance),
                                    BaseInOdom(T_world_camera).rotation());
}

map::Keyframe BaseFrameConvention::KeyframeToOdom(map::Keyframe keyframe) const {
  keyframe.T_world_camera = ToOdom(keyframe.T_world_camera);
  return keyframe;
}

map::KeyframeUpdate BaseFrameConvention::UpdateFromOdom(map::KeyframeUpdate update) const {
  for (auto& [id, pose] : update.keyframe_poses) pose = FromOdom(pose);
  for (auto& [id, position] : update.point_positions) position = FromOdom(position);
  return update;
}

}  // namespace stereo_fabmap_slam::ros_conversions
