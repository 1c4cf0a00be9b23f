// Tracker::ApplyUpdate: the backend's corrections reach the tracker's map and its motion model;
// the motion model spans skipped frames; a motion it does not predict is found by descriptor; a
// lost frame that still shows the map keeps it for the next frames, for a while; a keyframe due
// in the frames a busy caller will skip is taken before them; a pose found by descriptor far from
// the prediction needs a relocalization's evidence.
#include "stereo_fabmap_slam/odometry/tracker.h"

#include <string>
#include <utility>
#include <vector>

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

// A camera at `x` [m] to the side of the origin, turned `yaw_deg` to the right.
Eigen::Isometry3d SidewaysAndTurned(double x, double yaw_deg = 0) {
  Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
  pose.translation().x() = x;
  pose.linear() = Eigen::AngleAxisd(yaw_deg * M_PI / 180, Eigen::Vector3d::UnitY()).matrix();
  return pose;
}

// Points 3-8 m away across a wide wall, and a tracker (one thread) that has followed a camera
// sliding sideways past them 0.3 m every 10 ms for three frames (t = 0, 0.01, 0.02 s).
struct SlidingCamera {
  StereoWorld world;
  odometry::Tracker tracker;

  SlidingCamera()
      : tracker(SerialOptions(), odometry::KeyframePolicyOptions(), kCamera, cv::NORM_HAMMING,
                60.0) {
    world.Add(RandomPoints(3000, 7, /*half_width=*/24.0), 9);
    for (const int frame : {0, 1, 2}) {
      const odometry::TrackingResult result =
          tracker.Track(0.01 * frame, Observe(world, SidewaysAndTurned(0.3 * frame)));
      EXPECT_NE(result.state, odometry::TrackingState::kLost) << frame << ": " << result.reason;
    }
  }
  static odometry::TrackerOptions SerialOptions() {
    odometry::TrackerOptions options;
    options.parallel = false;
    return options;
  }
};

TEST(Tracker, SkippedFramesDoNotLoseTracking) {
  // After the three frames come three skipped ones (a busy tracker): 0.9 m of motion that a
  // prediction of one frame's motion misses by 51-137 px, beyond the widest search around it
  // (3 x 15 px). Only a motion model that spans the gap's time predicts the pose after it well
  // enough to find the frame by projection.
  SlidingCamera camera;
  const odometry::TrackingResult after_gap =
      camera.tracker.Track(0.06, Observe(camera.world, SidewaysAndTurned(1.8)));
  EXPECT_NE(after_gap.state, odometry::TrackingState::kLost) << after_gap.reason;
  EXPECT_FALSE(after_gap.keyframe && after_gap.keyframe->starts_new_segment) << after_gap.reason;
  EXPECT_EQ(after_gap.reason.find("by descriptor"), std::string::npos) << after_gap.reason;
  EXPECT_LT((after_gap.T_world_camera.translation() - SidewaysAndTurned(1.8).translation()).norm(),
            1e-3);
}

// The frames at which a tracker that sees the `tracked` frames (increasing, from 0) of a camera
// sliding sideways 4 cm a frame (20 Hz) takes keyframes, with only the translation bound
// (0.25 m) on, and why.
std::vector<std::pair<int, std::string>> TranslationKeyframes(const std::vector<int>& tracked) {
  odometry::TrackerOptions options;
  options.parallel = false;
  odometry::KeyframePolicyOptions keyframes;
  keyframes.min_tracked_ratio = 0;
  keyframes.min_tracked_points = 0;
  keyframes.max_rotation_deg = 180;
  keyframes.max_interval = 100;
  odometry::Tracker tracker(options, keyframes, kCamera, cv::NORM_HAMMING, 60.0);
  StereoWorld world;
  world.Add(RandomPoints(3000, 7, /*half_width=*/24.0), 9);
  std::vector<std::pair<int, std::string>> taken;
  int previous = 0;
  for (const int frame : tracked) {
    const odometry::TrackingResult result =
        tracker.Track(0.05 * frame, Observe(world, SidewaysAndTurned(0.04 * frame)),
                      frame == 0 ? 0 : frame - previous - 1);
    previous = frame;
    EXPECT_EQ(result.state, odometry::TrackingState::kOk) << frame << ": " << result.reason;
    if (result.keyframe && frame > 0) taken.emplace_back(frame, result.reason);
  }
  return taken;
}

TEST(Tracker, AKeyframeDueInFramesToBeSkippedIsTakenBeforeThem) {
  // Every frame: the bound is crossed at frame 7 (0.28 m). Every 3rd frame: frame 6 (0.24 m) is
  // the last tracked before it, and the frames 7-8 the tracker will skip cross it (0.28 m at
  // frame 7): the keyframe is taken at 6, not at 9 (0.36 m). At frame 3 the skipped frames
  // reach 0.20 m only: no keyframe.
  const std::vector<std::pair<int, std::string>> every_frame =
      TranslationKeyframes({0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12});
  ASSERT_FALSE(every_frame.empty());
  EXPECT_EQ(every_frame[0].first, 7);
  EXPECT_NE(every_frame[0].second.find("keyframe: translation"), std::string::npos)
      << every_frame[0].second;
  const std::vector<std::pair<int, std::string>> every_third =
      TranslationKeyframes({0, 3, 6, 9, 12});
  ASSERT_FALSE(every_third.empty());
  EXPECT_EQ(every_third[0].first, 6);
  EXPECT_NE(every_third[0].second.find("keyframe: translation before the next tracked frame"),
            std::string::npos)
      << every_third[0].second;
}

TEST(Tracker, AKeyframeIsTakenBeforeALongerGapThanTheLastOne) {
  // A tracker slower than the camera by a fraction skips a varying number of frames: here two,
  // none, none, two. At frame 5 (0.20 m) it skipped none, but skipped two shortly before, and
  // frames 6-7, which it will skip, cross the bound (0.28 m at frame 7): the keyframe is taken
  // at 5. Guessing from the last gap alone (none) took it at 8 (0.32 m), a gap later than at
  // every frame (7). At frame 4 the guess reaches frame 6, 0.24 m: no keyframe.
  const std::vector<std::pair<int, std::string>> taken = TranslationKeyframes({0, 3, 4, 5, 8});
  ASSERT_FALSE(taken.empty());
  EXPECT_EQ(taken[0].first, 5) << taken[0].second;
  EXPECT_NE(taken[0].second.find("keyframe: translation before the next tracked frame"),
            std::string::npos)
      << taken[0].second;
}

TEST(Tracker, AMotionTheModelMissesIsFoundByDescriptor) {
  // Over the 40 ms after the three frames (three skipped) the camera stops and turns 8 degrees
  // to the right. The prediction, 1.2 m further to the right and not turned, puts every point
  // 69-183 px (1.2 m at 3-8 m, fx 458) and 64 px (the turn) from where it is, far beyond the
  // widest search around it (3 x 15 px): by projection alone the frame would start a new map.
  // Found by descriptor 1.2 m from the prediction, beyond max_descriptor_jump, the pose has a
  // relocalization's evidence: hundreds of inliers over the whole image.
  SlidingCamera camera;
  const Eigen::Isometry3d turned = SidewaysAndTurned(0.6, -8.0);
  const odometry::TrackingResult after = camera.tracker.Track(0.06, Observe(camera.world, turned));
  EXPECT_EQ(after.state, odometry::TrackingState::kOk) << after.reason;
  EXPECT_NE(after.reason.find("found by descriptor"), std::string::npos) << after.reason;
  EXPECT_FALSE(after.keyframe && after.keyframe->starts_new_segment) << after.reason;
  EXPECT_LT((after.T_world_camera.translation() - turned.translation()).norm(), 1e-3);
  EXPECT_LT(Eigen::AngleAxisd(after.T_world_camera.linear().transpose() * turned.linear()).angle(),
            1e-4);
  // The motion model now holds the stop and the turn (2 degrees, 16 px, per 10 ms): the next
  // frame 10 ms later, where the camera stopped turning, is within the wider search.
  const odometry::TrackingResult next = camera.tracker.Track(0.07, Observe(camera.world, turned));
  EXPECT_EQ(next.state, odometry::TrackingState::kOk) << next.reason;
  EXPECT_EQ(next.reason.find("by descriptor"), std::string::npos) << next.reason;
}

// A kidnapped camera 60 m away sees, among things the map never held, a copy of some of the
// map's points (a photograph the building repeats, identical doors): the points that a camera at
// x = -1.5 m, 2.4 m from where the motion model expects this frame, sees of the map within
// `window`, copied 60 m along x with their descriptors, and seen from 60 m further on.
features::StereoFeatures LookAlikeFarFromThePrediction(const StereoWorld& world,
                                                       const cv::Rect& window, int keep_every,
                                                       int* copied = nullptr) {
  const Eigen::Isometry3d look_alike_view = SidewaysAndTurned(-1.5);
  const Eigen::Vector3d offset(60.0, 0, 0);
  StereoWorld elsewhere;
  std::vector<Eigen::Vector3d> copies;
  std::vector<int> rows;
  int seen = 0;
  for (int i = 0; i < static_cast<int>(world.points.size()); ++i) {
    // In the map: seen from the first keyframe (x = 0) with both cameras.
    const Eigen::Vector3d in_map = world.points[i];
    const Eigen::Vector3d first = kCamera.Project(in_map);
    if (in_map.z() < 0.5 || first.x() < 0 || first.x() >= kCamera.size.width || first.y() < 0 ||
        first.y() >= kCamera.size.height || first.z() < 0) {
      continue;
    }
    const Eigen::Vector3d seen_there = kCamera.Project(look_alike_view.inverse() * in_map);
    if (!window.contains(
            cv::Point(static_cast<int>(seen_there.x()), static_cast<int>(seen_there.y()))))
      continue;
    if (seen++ % keep_every != 0) continue;
    copies.push_back(in_map + offset);
    rows.push_back(i);
  }
  cv::Mat descriptors(static_cast<int>(rows.size()), world.descriptors.cols, CV_8U);
  for (std::size_t k = 0; k < rows.size(); ++k) {
    world.descriptors.row(rows[k]).copyTo(descriptors.row(static_cast<int>(k)));
  }
  elsewhere.Add(copies, descriptors);
  if (copied) *copied = static_cast<int>(copies.size());
  std::vector<Eigen::Vector3d> other = RandomPoints(600, 31);
  for (Eigen::Vector3d& point : other) point += look_alike_view.translation() + offset;
  elsewhere.Add(other, 32);
  Eigen::Isometry3d kidnapped = look_alike_view;
  kidnapped.translation() += offset;
  return Observe(elsewhere, kidnapped);
}

TEST(Tracker, ALookAlikeFarFromThePredictionNeedsTheEvidenceOfARelocalization) {
  // Found by descriptor, the copies put the camera at x = -1.5 m, 2.4 m from the prediction
  // (0.9 m): more than max_descriptor_jump (1 m), so the pose must show a relocalization's
  // evidence, and these do not: a photograph, all of the copied points within a quarter of the
  // image (four cells of the 4 x 4 grid, fewer than jump_min_inlier_cells 6; 59 points, more
  // than min_inliers_ok 50), and 30 look-alikes scattered over the whole image (fewer than
  // min_inliers_ok, more than min_inliers_weak 15, which tracking near the prediction needs).
  // Either way the frame is lost, and as the prediction found nothing of the map, a new segment
  // starts at once.
  const struct {
    const char* what;
    cv::Rect window;
    int keep_every;
  } cases[] = {{"a photograph", cv::Rect(190, 122, 372, 236), 1},
               {"scattered look-alikes", cv::Rect(0, 0, 752, 480), 7}};
  for (const auto& look_alike : cases) {
    SlidingCamera camera;
    int copied = 0;
    const features::StereoFeatures frame = LookAlikeFarFromThePrediction(
        camera.world, look_alike.window, look_alike.keep_every, &copied);
    // What each case is about: the photograph has inliers enough, the scattered ones spread.
    EXPECT_GE(copied, look_alike.keep_every == 1 ? 50 : 16) << look_alike.what;
    const odometry::TrackingResult kidnapped = camera.tracker.Track(0.03, frame);
    EXPECT_EQ(kidnapped.state, odometry::TrackingState::kLost)
        << look_alike.what << ": " << kidnapped.reason;
    EXPECT_NE(kidnapped.reason.find("from the prediction: too far"), std::string::npos)
        << look_alike.what << ": " << kidnapped.reason;
    ASSERT_TRUE(kidnapped.keyframe.has_value()) << look_alike.what << ": " << kidnapped.reason;
    EXPECT_TRUE(kidnapped.keyframe->starts_new_segment) << look_alike.what;
  }
  // With max_descriptor_jump beyond the jump the look-alike is tracked, at the copy's pose:
  // what happened to a kidnapped camera in a hall that repeats its photographs.
  odometry::TrackerOptions trusting = SlidingCamera::SerialOptions();
  trusting.max_descriptor_jump = 10.0;
  odometry::Tracker tracker(trusting, odometry::KeyframePolicyOptions(), kCamera, cv::NORM_HAMMING,
                            60.0);
  SlidingCamera camera;
  for (const int frame : {0, 1, 2}) {
    tracker.Track(0.01 * frame, Observe(camera.world, SidewaysAndTurned(0.3 * frame)));
  }
  const odometry::TrackingResult fooled = tracker.Track(
      0.03, LookAlikeFarFromThePrediction(camera.world, cases[1].window, cases[1].keep_every));
  EXPECT_NE(fooled.state, odometry::TrackingState::kLost) << fooled.reason;
  EXPECT_LT((fooled.T_world_camera.translation() - Eigen::Vector3d(-1.5, 0, 0)).norm(), 0.05)
      << fooled.reason;
}

// A frame that still shows the map, too poorly to trust a pose (motion blur leaves a few of its
// corners): ten of the key points the camera at `T_world_camera` sees, and sixty of points the
// map does not hold, enough stereo points for a new map.
features::StereoFeatures Glimpse(const StereoWorld& world,
                                 const Eigen::Isometry3d& T_world_camera) {
  features::StereoFeatures glimpse = Observe(world, T_world_camera);
  constexpr std::size_t kSeen = 10;
  glimpse.keypoints.resize(kSeen);
  glimpse.u_right.resize(kSeen);
  glimpse.points.resize(kSeen);
  glimpse.descriptors = glimpse.descriptors.rowRange(0, kSeen).clone();
  StereoWorld unmapped;
  unmapped.Add(RandomPoints(60, 21), 22);
  const features::StereoFeatures other = Observe(unmapped, Eigen::Isometry3d::Identity());
  glimpse.keypoints.insert(glimpse.keypoints.end(), other.keypoints.begin(), other.keypoints.end());
  glimpse.u_right.insert(glimpse.u_right.end(), other.u_right.begin(), other.u_right.end());
  glimpse.points.insert(glimpse.points.end(), other.points.begin(), other.points.end());
  cv::vconcat(glimpse.descriptors, other.descriptors, glimpse.descriptors);
  return glimpse;
}

TEST(Tracker, AFrameThatShowsTooLittleOfTheMapKeepsItForTheNext) {
  // Ten of the frame's 600-odd map points: a consensus of 10, below min_inliers_weak (15), but
  // no chance agreement. The frame is lost; the map stays, and the next frame is tracked in it,
  // predicted over the 20 ms since the last tracked frame.
  SlidingCamera camera;
  const odometry::TrackingResult lost =
      camera.tracker.Track(0.03, Glimpse(camera.world, SidewaysAndTurned(0.9)));
  EXPECT_EQ(lost.state, odometry::TrackingState::kLost) << lost.reason;
  EXPECT_TRUE(lost.map_kept) << lost.reason;
  EXPECT_FALSE(lost.keyframe.has_value()) << lost.reason;
  EXPECT_NE(lost.reason.find("map kept"), std::string::npos) << lost.reason;

  const odometry::TrackingResult next =
      camera.tracker.Track(0.04, Observe(camera.world, SidewaysAndTurned(1.2)));
  EXPECT_EQ(next.state, odometry::TrackingState::kOk) << next.reason;
  EXPECT_FALSE(next.keyframe && next.keyframe->starts_new_segment) << next.reason;
  EXPECT_LT((next.T_world_camera.translation() - SidewaysAndTurned(1.2).translation()).norm(),
            1e-3);
}

TEST(Tracker, AFrameThatShowsNothingOfTheMapStartsANewPieceAtOnce) {
  // A kidnapped camera: other points, other descriptors. No consensus at all, so nothing says
  // the camera still sees the map: a new piece starts with this frame, for relocalization to
  // join to the map.
  SlidingCamera camera;
  StereoWorld elsewhere;
  elsewhere.Add(RandomPoints(600, 11), 12);
  const odometry::TrackingResult kidnapped =
      camera.tracker.Track(0.03, Observe(elsewhere, Eigen::Isometry3d::Identity()));
  EXPECT_FALSE(kidnapped.map_kept) << kidnapped.reason;
  ASSERT_TRUE(kidnapped.keyframe.has_value()) << kidnapped.reason;
  EXPECT_TRUE(kidnapped.keyframe->starts_new_segment) << kidnapped.reason;
}

TEST(Tracker, TheMapIsKeptNoLongerThanMaxTimeLost) {
  // Glimpses of the map keep it until max_time_lost (0.5 s) has passed since
  // the last tracked frame (t = 0.02 s); the next starts a new piece.
  SlidingCamera camera;
  const features::StereoFeatures glimpse = Glimpse(camera.world, SidewaysAndTurned(0.9));
  for (const double t : {0.1, 0.3, 0.45}) {
    const odometry::TrackingResult lost = camera.tracker.Track(t, glimpse);
    EXPECT_TRUE(lost.map_kept) << t << ": " << lost.reason;
  }
  const odometry::TrackingResult late = camera.tracker.Track(0.55, glimpse);
  EXPECT_FALSE(late.map_kept) << late.reason;
  ASSERT_TRUE(late.keyframe.has_value()) << late.reason;
  EXPECT_TRUE(late.keyframe->starts_new_segment) << late.reason;
}

}  // namespace
}  // namespace stereo_fabmap_slam::test
