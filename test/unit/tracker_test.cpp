// Tracker::ApplyUpdate: the backend's corrections reach the tracker's map and its motion model.
#include "stereo_fabmap_slam/odometry/tracker.h"

#include <gtest/gtest.h>
#include <opencv2/core.hpp>

#include "stereo_world.h"

namespace stereo_fabmap_slam::test {
namespace {

const geometry::StereoCamera& kCamera = kTestCamera;

StereoWorld MakeWorld(int count) {
  StereoWorld world;
  world.Add(RandomPoints(count, 3), 5);
  return world;
}

TEST(Tracker, ApplyUpdateMovesTheMapAndTheMotionModel) {
  const StereoWorld world = MakeWorld(300);
  odometry::TrackerOptions options;
  options.parallel = false;
  odometry::Tracker tracker(options, odometry::KeyframePolicyOptions(), kCamera, cv::NORM_HAMMING,
                            60.0);
  const Eigen::Isometry3d start = Eigen::Isometry3d::Identity();
  const odometry::TrackingResult first = tracker.Track(0.0, Observe(world, start));
  ASSERT_TRUE(first.keyframe.has_value());
  ASSERT_GT(first.keyframe->features.CountWithDepth(), 200);

  // The backend moves keyframe 0, and every point with it, by a rigid correction.
  Eigen::Isometry3d correction = Eigen::Isometry3d::Identity();
  correction.linear() = Eigen::AngleAxisd(0.02, Eigen::Vector3d::UnitY()).toRotationMatrix();
  correction.translation() = Eigen::Vector3d(0.08, -0.02, 0.05);
  map::KeyframeUpdate update;
  update.keyframe_poses.emplace_back(first.keyframe->id,
                                     correction * first.keyframe->T_world_camera);
  for (std::size_t i = 0; i < first.keyframe->map_point_ids.size(); ++i) {
    const std::int64_t id = first.keyframe->map_point_ids[i];
    if (id >= 0) {
      update.point_positions.emplace_back(
          id, correction * first.keyframe->T_world_camera * first.keyframe->features.points[i]);
    }
  }
  tracker.ApplyUpdate(update);

  // The camera has not moved: in the corrected map it stands where the correction put the
  // keyframe. Without the update the pose would be the identity, 9.6 cm away.
  const odometry::TrackingResult second = tracker.Track(0.05, Observe(world, start));
  ASSERT_NE(second.state, odometry::TrackingState::kLost) << second.reason;
  const Eigen::Isometry3d expected = correction * start;
  EXPECT_LT((second.T_world_camera.translation() - expected.translation()).norm(), 1e-3);
  EXPECT_LT(
      Eigen::AngleAxisd(second.T_world_camera.linear().transpose() * expected.linear()).angle(),
      1e-3);
  EXPECT_EQ(second.reference_keyframe, first.keyframe->id);
  EXPECT_TRUE(second.T_keyframe_camera.isApprox(Eigen::Isometry3d::Identity(), 1e-3));
}

TEST(Tracker, ApplyUpdateWithoutAMapChangesNothing) {
  odometry::Tracker tracker(odometry::TrackerOptions(), odometry::KeyframePolicyOptions(), kCamera,
                            cv::NORM_HAMMING, 60.0);
  map::KeyframeUpdate update;
  update.keyframe_poses.emplace_back(0, Eigen::Isometry3d::Identity());
  EXPECT_NO_THROW(tracker.ApplyUpdate(update));
  const odometry::TrackingResult first =
      tracker.Track(0.0, Observe(MakeWorld(300), Eigen::Isometry3d::Identity()));
  EXPECT_TRUE(first.keyframe.has_value());
  EXPECT_TRUE(first.T_world_camera.isApprox(Eigen::Isometry3d::Identity()));
}

}  // namespace
}  // namespace stereo_fabmap_slam::test
