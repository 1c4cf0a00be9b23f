// The StereoTracker and Backend nodelets on a real bag: odometry for nearly every frame,
// keyframes on their topic, and the same final pose as the offline runner within 5 cm. The
// odometry is the body's (REP-105: odom -> base_link, the camera's mounting a static transform)
// and follows the ground truth of the body, with a covariance that is not zero.
#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <map>
#include <mutex>
#include <string>

#include <gtest/gtest.h>
#include <nav_msgs/Odometry.h>
#include <ros/ros.h>
#include <stereo_fabmap_slam/Keyframe.h>
#include <stereo_fabmap_slam/TrackedFrame.h>
#include <tf2_ros/buffer.h>
#include <tf2_ros/transform_listener.h>

#include "euroc_bag_fixture.h"
#include "ros_conversions.h"
#include "stereo_fabmap_slam/camera/camera_calibration.h"
#include "stereo_fabmap_slam/camera/stereo_rectifier.h"
#include "stereo_fabmap_slam/datasets/euroc_sequence.h"
#include "stereo_fabmap_slam/io/trajectory_file.h"
#include "test_support.h"

namespace stereo_fabmap_slam::test {
namespace {

// MH01_first10s as a bag, and the offline runner's odometry of it to compare with.
class EurocOdometry : public ::testing::Test {
 protected:
  void SetUp() override {
    asl_ = EurocSequencePath("MH01_first10s");
    bag_ = temp_.path() + "/mh01.bag";
    WriteEurocSubsetBag("MH01_first10s", bag_);
    std::string output;
    ASSERT_EQ(RunCommand(std::string(RUN_DATASET_BIN) + " " + asl_ + " --quiet --output " +
                             temp_.path() + "/offline 2>&1",
                         &output),
              0)
        << output;
    offline_ = io::ReadTumTrajectory(temp_.path() + "/offline/odometry.txt");
  }

  // The offline runner's camera pose (in its first camera pose) at an image stamp.
  Eigen::Isometry3d OfflinePose(std::int64_t stamp_ns) const {
    for (const io::StampedPose& p : offline_) {
      if (std::llabs(static_cast<std::int64_t>(std::llround(p.timestamp * 1e9)) - stamp_ns) < 1000)
        return p.pose;
    }
    ADD_FAILURE() << "offline trajectory has no pose at " << stamp_ns;
    return Eigen::Isometry3d::Identity();
  }

  TemporaryDirectory temp_;
  std::string asl_, bag_;
  io::Trajectory offline_;
};

TEST_F(EurocOdometry, BagThroughNodeletsMatchesOfflineRunner) {
  const std::string& asl = asl_;
  const std::string& bag = bag_;
  TemporaryDirectory& temp = temp_;

  std::mutex mutex;
  std::map<std::int64_t, Eigen::Isometry3d> online;  // by stamp [ns]
  nav_msgs::Odometry last_message;
  int keyframes = 0;
  ros::NodeHandle node;
  const ros::Subscriber odometry_subscriber = node.subscribe<nav_msgs::Odometry>(
      "/odometry", 1000, [&](const nav_msgs::OdometryConstPtr& message) {
        std::lock_guard<std::mutex> lock(mutex);
        online[ros_conversions::ToNanoseconds(message->header.stamp)] =
            ros_conversions::FromPoseMessage(message->pose.pose);
        last_message = *message;
      });
  const ros::Subscriber keyframe_subscriber = node.subscribe<stereo_fabmap_slam::Keyframe>(
      "/keyframes", 1000, [&](const stereo_fabmap_slam::KeyframeConstPtr&) {
        std::lock_guard<std::mutex> lock(mutex);
        ++keyframes;
      });
  tf2_ros::Buffer tf_buffer;
  tf2_ros::TransformListener tf_listener(tf_buffer);
  ros::AsyncSpinner spinner(2);
  spinner.start();
  // Blocks until the bag has played (exit_at_end: the player's end ends the launch).
  const int status = std::system(
      ("roslaunch --wait stereo_fabmap_slam euroc_bag.launch exit_at_end:=true bag:=" + bag +
       " > " + temp.path() + "/roslaunch.log 2>&1")
          .c_str());
  EXPECT_EQ(status, 0) << ReadTextFile(temp.path() + "/roslaunch.log");
  ros::WallDuration(1.0).sleep();
  spinner.stop();

  // The camera's mounting: the rectified left camera in the base, which sits at the body (IMU)
  // origin, level (T_body_base of the calibration).
  const camera::StereoCalibration calibration = camera::ReadStereoCalibrationYaml(
      std::string(STEREO_FABMAP_SLAM_REPO_ROOT) + "/config/euroc_stereo.yaml");
  const Eigen::Isometry3d T_base_body = calibration.T_body_base.inverse();
  const Eigen::Isometry3d T_base_camera =
      T_base_body *
      camera::StereoRectifier::FromCalibration(calibration, camera::RectificationOptions())
          .T_body_rectified_left();
  std::string tf_error;
  ASSERT_TRUE(tf_buffer.canTransform("base_link", "camera_optical", ros::Time(0), &tf_error))
      << tf_error;
  const Eigen::Isometry3d published_mount = ros_conversions::FromTransformMessage(
      tf_buffer.lookupTransform("base_link", "camera_optical", ros::Time(0)).transform);
  EXPECT_TRUE(published_mount.isApprox(T_base_camera, 1e-6));
  EXPECT_TRUE(tf_buffer.canTransform("odom", "base_link", ros::Time(0)));

  std::lock_guard<std::mutex> lock(mutex);
  RecordProperty("odometry_messages", static_cast<int>(online.size()));
  RecordProperty("keyframes", keyframes);
  EXPECT_GE(online.size(), 190u) << ReadTextFile(temp.path() + "/roslaunch.log");  // 95 % of 200
  EXPECT_GT(keyframes, 5);
  ASSERT_GE(online.size(), 2u);
  EXPECT_EQ(last_message.header.frame_id, "odom");
  EXPECT_EQ(last_message.child_frame_id, "base_link");
  // Hundreds of inliers with 1 px noise pin a frame down to millimetres: positive, below 1 cm.
  for (int k = 0; k < 3; ++k) {
    const double variance = last_message.pose.covariance[static_cast<std::size_t>(7 * k)];
    EXPECT_GT(variance, 0.0) << k;
    EXPECT_LT(variance, 1e-4) << k;
  }

  // Both runs start their world at their first tracked frame; compare the motion from the
  // online run's first to its last frame.
  // online: the body in odom; offline: the camera in its own first pose.
  const auto first = online.begin(), last = std::prev(online.end());
  const Eigen::Isometry3d online_motion = first->second.inverse() * last->second;
  const Eigen::Isometry3d offline_motion = T_base_camera * OfflinePose(first->first).inverse() *
                                           OfflinePose(last->first) * T_base_camera.inverse();
  const double difference = (online_motion.translation() - offline_motion.translation()).norm();
  RecordProperty("final_pose_difference_m", std::to_string(difference));
  EXPECT_LT(difference, 0.05);

  // The base's motion against the ground truth's (moved from EuRoC's body, the IMU, to the
  // base); 10 s of odometry drift by a few centimetres at most. The nearest pose of the 200 Hz
  // ground truth: within 2.5 ms, a millimetre at these speeds.
  const datasets::EurocSequence sequence = datasets::EurocSequence::Open(asl);
  const auto ground_truth_at = [&](std::int64_t stamp_ns) {
    const io::Trajectory& truth = sequence.ground_truth();
    const auto nearest =
        std::min_element(truth.begin(), truth.end(), [&](const auto& a, const auto& b) {
          return std::abs(a.timestamp - stamp_ns * 1e-9) < std::abs(b.timestamp - stamp_ns * 1e-9);
        });
    EXPECT_LT(std::abs(nearest->timestamp - stamp_ns * 1e-9), 0.005);
    return nearest->pose;
  };
  const Eigen::Isometry3d true_motion = T_base_body * ground_truth_at(first->first).inverse() *
                                        ground_truth_at(last->first) * T_base_body.inverse();
  const double ground_truth_difference =
      (online_motion.translation() - true_motion.translation()).norm();
  RecordProperty("motion_m", std::to_string(true_motion.translation().norm()));
  RecordProperty("ground_truth_difference_m", std::to_string(ground_truth_difference));
  // 4.9 mm measured over 0.39 m; 1.5 cm is three times that. A mount turned by a few degrees
  // would turn the motion vector by as much (2 cm per 3 degrees here) and fail.
  EXPECT_LT(ground_truth_difference, 0.015) << "true motion " << true_motion.translation().norm();
  const double rotation_error_deg =
      Eigen::AngleAxisd(true_motion.rotation().transpose() * online_motion.rotation()).angle() *
      180.0 / M_PI;
  RecordProperty("ground_truth_rotation_difference_deg", std::to_string(rotation_error_deg));
  EXPECT_LT(rotation_error_deg, 1.0);
}

// The same bag with the calibration from its camera_info (written by euroc_to_bag, found
// beside the remapped image topics): tracked as well, with the camera as the base (camera_info
// carries no mounting), so the camera's motion matches the offline runner's.
TEST_F(EurocOdometry, CalibrationFromTheBagsCameraInfo) {
  const std::string& bag = bag_;
  TemporaryDirectory& temp = temp_;
  std::mutex mutex;
  std::map<std::int64_t, Eigen::Isometry3d> online;
  std::size_t refused = 0;  // pairs before the camera_info made the calibration
  ros::NodeHandle node;
  const ros::Subscriber odometry_subscriber = node.subscribe<nav_msgs::Odometry>(
      "/odometry", 1000, [&](const nav_msgs::OdometryConstPtr& message) {
        std::lock_guard<std::mutex> lock(mutex);
        online[ros_conversions::ToNanoseconds(message->header.stamp)] =
            ros_conversions::FromPoseMessage(message->pose.pose);
      });
  const ros::Subscriber frame_subscriber = node.subscribe<stereo_fabmap_slam::TrackedFrame>(
      "/tracked_frames", 1000, [&](const stereo_fabmap_slam::TrackedFrameConstPtr& message) {
        std::lock_guard<std::mutex> lock(mutex);
        refused += message->tracked ? 0 : 1;
      });
  ros::AsyncSpinner spinner(1);
  spinner.start();
  const int status = std::system(("roslaunch --wait stereo_fabmap_slam euroc_bag.launch "
                                  "exit_at_end:=true use_camera_info:=true"
                                  " visualizer:=false bag:=" +
                                  bag + " > " + temp.path() + "/roslaunch.log 2>&1")
                                     .c_str());
  EXPECT_EQ(status, 0) << ReadTextFile(temp.path() + "/roslaunch.log");
  ros::WallDuration(1.0).sleep();
  spinner.stop();
  std::lock_guard<std::mutex> lock(mutex);
  RecordProperty("odometry_messages", static_cast<int>(online.size()));
  RecordProperty("pairs_refused", static_cast<int>(refused));
  // The first camera_info pair arrives with the first images: a pair taken before the
  // calibration is made from it is refused, with a tracked_frames message saying so. A pair the
  // tracker had no time for is skipped and reported ("N skipped in all", at most once a second,
  // so the last skips of the bag may go unreported when the launch ends with it, as may the
  // pairs still queued then). That every pair is counted is the queue's and the stage's
  // (ros_wiring_test, tracking_stage_test); here the tracker must keep up at 1x.
  const std::string log = ReadTextFile(temp.path() + "/roslaunch.log");
  const std::size_t reported = log.rfind(" skipped in all");
  std::size_t skipped = 0;
  if (reported != std::string::npos) {
    const std::size_t start = log.find_last_not_of("0123456789", reported - 1) + 1;
    skipped = std::stoul(log.substr(start, reported - start));
  }
  RecordProperty("pairs_skipped", static_cast<int>(skipped));
  // camera_info says nothing of where the camera sits: the user hears that base_link is the
  // camera (not REP-103's x forward, z up) and how to say otherwise.
  EXPECT_NE(log.find("use_camera_info without ~base_to_camera"), std::string::npos) << log;
  // The calibration is made within a frame or two of the first camera_info (rectification maps:
  // tens of milliseconds; 0 or 1 pair refused in three full make test runs); 5 % allows for a
  // loaded machine.
  EXPECT_LE(refused, 10u) << log;
  // Keeping up at 1x, as load_test's 1x run: inside full make test runs, beside the sanitizer
  // build, 196-198 pairs had odometry (2-4 skipped, 0-1 refused) and one run 187 (7 skipped
  // reported, 6 more at the end of the bag unreported or still queued); 90 % still tells a
  // tracker that keeps up from one that does not.
  EXPECT_GE(online.size(), 180u) << log;
  ASSERT_GE(online.size(), 2u);
  // The base is the raw left camera, the offline runner's the rectified one: the same origin,
  // so the distances travelled agree (the offline run starts a frame or two earlier).
  // The same for the rotation angle of the motion (unchanged by a change of frame).
  const auto first = online.begin(), last = std::prev(online.end());
  const Eigen::Isometry3d online_motion = first->second.inverse() * last->second;
  const Eigen::Isometry3d offline_motion =
      OfflinePose(first->first).inverse() * OfflinePose(last->first);
  const double online_distance = online_motion.translation().norm();
  const double offline_distance = offline_motion.translation().norm();
  RecordProperty("distance_difference_m", std::to_string(online_distance - offline_distance));
  EXPECT_NEAR(online_distance, offline_distance, 0.01);
  EXPECT_NEAR(Eigen::AngleAxisd(online_motion.rotation()).angle(),
              Eigen::AngleAxisd(offline_motion.rotation()).angle(), 0.2 * M_PI / 180.0);
}

}  // namespace
}  // namespace stereo_fabmap_slam::test

int main(int argc, char** argv) {
  testing::InitGoogleTest(&argc, argv);
  ros::init(argc, argv, "euroc_odometry_test");
  return RUN_ALL_TESTS();
}
