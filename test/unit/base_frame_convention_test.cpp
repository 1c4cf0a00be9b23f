// REP-105 frames of the tracker's output: a robot driving a known path, seen through a camera
// mounted on it, comes out as that path in odom, with its twist and a covariance that is not
// zero.
#include "base_frame_convention.h"

#include <gtest/gtest.h>

#include "odometry_message_builder.h"
#include "ros_conversions.h"

namespace stereo_fabmap_slam::test {
namespace {

using ros_conversions::BaseFrameConvention;

// A camera looking forward from a robot whose x axis is forward and z up, mounted 0.2 m ahead
// and 0.5 m up: optical z along base x, optical x along base -y, optical y along base -z.
Eigen::Isometry3d ForwardCameraMount() {
  Eigen::Isometry3d T_base_camera = Eigen::Isometry3d::Identity();
  T_base_camera.linear() << 0, 0, 1, -1, 0, 0, 0, -1, 0;
  T_base_camera.translation() = Eigen::Vector3d(0.2, 0.0, 0.5);
  return T_base_camera;
}

// The robot drives at 1 m/s forward while turning left at 0.5 rad/s.
Eigen::Isometry3d BaseAt(double t) {
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  const double heading = 0.5 * t;
  T.linear() = Eigen::AngleAxisd(heading, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  T.translation() = Eigen::Vector3d(std::sin(heading), 1.0 - std::cos(heading), 0.0) / 0.5;
  return T;
}

// What the library reports: the camera in a world that is the camera at the first frame.
Eigen::Isometry3d LibraryCameraPose(const Eigen::Isometry3d& T_base_camera, double t) {
  return T_base_camera.inverse() * BaseAt(t) * T_base_camera;
}

TEST(BaseFrameConvention, TheRobotsPathComesOutInOdom) {
  const BaseFrameConvention frames(ForwardCameraMount());
  for (double t : {0.0, 0.7, 2.5}) {
    EXPECT_TRUE(
        frames.BaseInOdom(LibraryCameraPose(frames.T_base_camera(), t)).isApprox(BaseAt(t), 1e-12))
        << t;
  }
  // A camera pose in odom is the base pose times the mounting.
  EXPECT_TRUE(frames.ToOdom(LibraryCameraPose(frames.T_base_camera(), 1.0))
                  .isApprox(BaseAt(1.0) * frames.T_base_camera(), 1e-12));
}

TEST(BaseFrameConvention, KeyframesAndUpdatesRoundTrip) {
  const BaseFrameConvention frames(ForwardCameraMount());
  map::Keyframe keyframe;
  keyframe.T_world_camera = LibraryCameraPose(frames.T_base_camera(), 1.3);
  const map::Keyframe in_odom = frames.KeyframeToOdom(keyframe);
  map::KeyframeUpdate update;
  update.keyframe_poses.emplace_back(4, in_odom.T_world_camera);
  update.point_positions.emplace_back(9, frames.ToOdom(Eigen::Vector3d(1, 2, 3)));
  const map::KeyframeUpdate back = frames.UpdateFromOdom(update);
  EXPECT_TRUE(back.keyframe_poses[0].second.isApprox(keyframe.T_world_camera, 1e-12));
  EXPECT_TRUE(back.point_positions[0].second.isApprox(Eigen::Vector3d(1, 2, 3), 1e-12));
}

// A camera that is unsure only of its depth (optical z, the base's forward x): once the robot
// has turned left by 90 degrees, that uncertainty is along odom's y.
TEST(BaseFrameConvention, CovarianceFollowsTheMountAndTheHeading) {
  const BaseFrameConvention frames(ForwardCameraMount());
  geometry::PoseCovariance depth_only = geometry::PoseCovariance::Zero();
  depth_only.diagonal() << 1e-6, 1e-6, 1e-4, 0, 0, 0;
  const double quarter_turn = M_PI / 2 / 0.5;  // BaseAt turns 0.5 rad/s
  const geometry::PoseCovariance in_odom = frames.BaseCovarianceInOdom(
      LibraryCameraPose(frames.T_base_camera(), quarter_turn), depth_only);
  EXPECT_NEAR(in_odom(1, 1), 1e-4, 1e-10);
  EXPECT_NEAR(in_odom(0, 0), 1e-6, 1e-10);
  EXPECT_NEAR(in_odom(2, 2), 1e-6, 1e-10);
}

TEST(OdometryMessageBuilder, TwistAndCovarianceOfTheBase) {
  const BaseFrameConvention frames(ForwardCameraMount());
  ros_conversions::OdometryMessageBuilder builder(frames, "odom", "base_link");
  // 1 cm and 0.1 degree in the camera's axes, independent.
  geometry::PoseCovariance camera_covariance = geometry::PoseCovariance::Zero();
  camera_covariance.diagonal() << 1e-4, 1e-4, 1e-4, 3e-6, 3e-6, 3e-6;
  const nav_msgs::Odometry first = builder.Build(
      ros::Time(10.0), LibraryCameraPose(frames.T_base_camera(), 0.0), camera_covariance, true);
  EXPECT_EQ(first.header.frame_id, "odom");
  EXPECT_EQ(first.child_frame_id, "base_link");
  EXPECT_GE(first.twist.covariance[0], 1e5) << "no twist is known from one frame";
  const nav_msgs::Odometry second = builder.Build(
      ros::Time(10.05), LibraryCameraPose(frames.T_base_camera(), 0.05), camera_covariance, true);
  const Eigen::Isometry3d pose = ros_conversions::FromPoseMessage(second.pose.pose);
  EXPECT_TRUE(pose.isApprox(BaseAt(0.05), 1e-9));
  // Forward 1 m/s, turning 0.5 rad/s about z (a chord of the arc: within 0.1 %).
  EXPECT_NEAR(second.twist.twist.linear.x, 1.0, 1e-3);
  EXPECT_NEAR(second.twist.twist.linear.y, 0.0, 0.02);
  EXPECT_NEAR(second.twist.twist.angular.z, 0.5, 1e-9);
  // The camera's rotation noise reaches the base's position through the 0.54 m lever arm, so
  // the base's position variance is above the camera's; every variance is positive.
  for (int k = 0; k < 6; ++k) EXPECT_GT(second.pose.covariance[7 * k], 0.0) << k;
  EXPECT_GT(second.pose.covariance[0], 1e-4);
  EXPECT_NEAR(second.pose.covariance[0], 1e-4 + 3e-6 * 0.5 * 0.5, 1e-6);  // x: y/z noise of 0.5 m
  // The twist of two poses 50 ms apart: (C + C) / dt^2.
  EXPECT_NEAR(second.twist.covariance[35], 2 * 3e-6 / (0.05 * 0.05), 1e-9);
  // After a jump no twist is claimed.
  const nav_msgs::Odometry jumped = builder.Build(
      ros::Time(10.1), LibraryCameraPose(frames.T_base_camera(), 3.0), camera_covariance, false);
  EXPECT_DOUBLE_EQ(jumped.twist.twist.linear.x, 0.0);
  EXPECT_GE(jumped.twist.covariance[0], 1e5);
}

}  // namespace
}  // namespace stereo_fabmap_slam::test
