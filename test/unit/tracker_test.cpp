// Tracker::ApplyUpdate: the backend's corrections reach the tracker's map and its motion model.
#include "stereo_fabmap_slam/odometry/tracker.h"

#include <random>

#include <gtest/gtest.h>
#include <opencv2/core.hpp>

namespace stereo_fabmap_slam::test {
namespace {

const geometry::StereoCamera kCamera{cv::Size(752, 480), 458.0, 458.0, 376.0, 240.0, 0.11};

// A world of points with distinct random binary descriptors (64 bytes: ~256 bits apart, far
// beyond the match limit, so every match is the true one).
struct World {
  std::vector<Eigen::Vector3d> points;
  cv::Mat descriptors;
};

World MakeWorld(int count) {
  std::mt19937 random(3);
  std::uniform_real_distribution<double> lateral(-2.5, 2.5), depth(3.0, 8.0);
  World world;
  world.descriptors = cv::Mat(count, 64, CV_8U);
  cv::RNG rng(5);
  rng.fill(world.descriptors, cv::RNG::UNIFORM, 0, 256);
  for (int i = 0; i < count; ++i) {
    world.points.emplace_back(lateral(random), 0.6 * lateral(random), depth(random));
  }
  return world;
}

// What the extractor would find in a frame taken at T_world_camera: every visible point with
// its stereo match.
features::StereoFeatures Observe(const World& world, const Eigen::Isometry3d& T_world_camera) {
  features::StereoFeatures features;
  std::vector<int> rows;
  for (int i = 0; i < static_cast<int>(world.points.size()); ++i) {
    const Eigen::Vector3d c = T_world_camera.inverse() * world.points[i];
    if (c.z() < 0.5) continue;
    const Eigen::Vector3d uvr = kCamera.Project(c);
    if (uvr.x() < 0 || uvr.y() < 0 || uvr.x() >= 752 || uvr.y() >= 480 || uvr.z() < 0) continue;
    features.keypoints.emplace_back(static_cast<float>(uvr.x()), static_cast<float>(uvr.y()), 7.f);
    features.u_right.push_back(static_cast<float>(uvr.z()));
    features.points.push_back(c);
    rows.push_back(i);
  }
  features.descriptors = cv::Mat(static_cast<int>(rows.size()), 64, CV_8U);
  for (std::size_t k = 0; k < rows.size(); ++k) {
    world.descriptors.row(rows[k]).copyTo(features.descriptors.row(static_cast<int>(k)));
  }
  return features;
}

TEST(Tracker, ApplyUpdateMovesTheMapAndTheMotionModel) {
  const World world = MakeWorld(300);
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
