#include "odometry_message_builder.h"

#include "ros_conversions.h"

namespace stereo_fabmap_slam::ros_conversions {
namespace {

constexpr double kUnknownVariance = 1e6;

void CopyCovariance(const geometry::PoseCovariance& covariance, boost::array<double, 36>* out) {
  for (int r = 0; r < 6; ++r) {
    for (int c = 0; c < 6; ++c) (*out)[static_cast<std::size_t>(6 * r + c)] = covariance(r, c);
  }
}

}  // namespace

nav_msgs::Odometry OdometryMessageBuilder::Build(const ros::Time& stamp,
                                                 const Eigen::Isometry3d& T_world_camera,
                                                 const geometry::PoseCovariance& camera_covariance,
                                                 bool continues_previous) {
  nav_msgs::Odometry odometry;
  odometry.header.stamp = stamp;
  odometry.header.frame_id = odom_frame_;
  odometry.child_frame_id = base_frame_;
  const Eigen::Isometry3d T_odom_base = frames_.BaseInOdom(T_world_camera);
  odometry.pose.pose = ToPoseMessage(T_odom_base);
  // Carried to the base once: the pose's covariance turns it into odom's axes, the twist's
  // keeps it in the base's.
  const geometry::PoseCovariance covariance_in_base = frames_.BaseCovariance(camera_covariance);
  CopyCovariance(geometry::RotateCovariance(covariance_in_base, T_odom_base.rotation()),
                 &odometry.pose.covariance);

  const double dt = previous_ ? (stamp - previous_->stamp).toSec() : 0.0;
  if (continues_previous && previous_ && dt > 0) {
    const Eigen::Isometry3d motion = previous_->T_odom_base.inverse() * T_odom_base;
    const Eigen::AngleAxisd rotation(motion.rotation());
    // In the current base_link's axes (nav_msgs: the twist is in child_frame_id); the rotation
    // vector is the same in both frames.
    const Eigen::Vector3d linear = motion.rotation().transpose() * motion.translation() / dt;
    const Eigen::Vector3d angular = rotation.angle() * rotation.axis() / dt;
    odometry.twist.twist.linear.x = linear.x();
    odometry.twist.twist.linear.y = linear.y();
    odometry.twist.twist.linear.z = linear.z();
    odometry.twist.twist.angular.x = angular.x();
    odometry.twist.twist.angular.y = angular.y();
    odometry.twist.twist.angular.z = angular.z();
    CopyCovariance((previous_->covariance_in_base + covariance_in_base) / (dt * dt),
                   &odometry.twist.covariance);
  } else {
    CopyCovariance(geometry::PoseCovariance::Identity() * kUnknownVariance,
                   &odometry.twist.covariance);
  }
  previous_ = Previous{stamp, T_odom_base, covariance_in_base};
  return odometry;
}

}  // namespace stereo_fabmap_slam::ros_conversions
