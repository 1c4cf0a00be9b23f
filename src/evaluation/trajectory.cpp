#include "stereo_fabmap_slam/evaluation/trajectory.h"

namespace stereo_fabmap_slam::evaluation {

Trajectory TransformToSensorFrame(const Trajectory& body_trajectory,
                                  const Eigen::Isometry3d& T_body_sensor) {
  Trajectory sensor_trajectory;
  sensor_trajectory.reserve(body_trajectory.size());
  for (const StampedPose& body : body_trajectory) {
    sensor_trajectory.push_back({body.timestamp, body.pose * T_body_sensor});
  }
  return sensor_trajectory;
}

}  // namespace stereo_fabmap_slam::evaluation
