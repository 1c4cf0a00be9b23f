// LoopDetector's geometric verification on stereo worlds with known geometry: a true revisit is
// accepted with the right relative pose; look-alikes elsewhere, which match perfectly by
// themselves, are rejected: a repeated room by the odometry check within one segment and, across
// segments, through the query segment's last loop; a repeated poster by the spread check even
// where nothing relates the two keyframes; candidates after an accepted one are not verified.
#include "stereo_fabmap_slam/place_recognition/loop_detector.h"

#include <algorithm>
#include <limits>
#include <string>

#include <gtest/gtest.h>
#include <opencv2/core.hpp>

#include "stereo_world.h"
#include "toy_place_recognition.h"

namespace stereo_fabmap_slam::test {
namespace {

using place_recognition::LoopCandidate;
using place_recognition::LoopDetection;

// A small vocabulary and Chow-Liu tree trained on random descriptors: FAB-MAP is not what these
// tests measure (every stored keyframe is verified: no floor, one view ranks alone).
place_recognition::LoopDetectorOptions DetectorOptions() {
  place_recognition::LoopDetectorOptions options;
  options.min_age = 5.0;
  options.min_probability = 0.0;
  options.min_log_odds = -std::numeric_limits<double>::infinity();
  options.sequence_length = 1;
  options.max_candidates = 5;
  return options;
}

place_recognition::LoopDetector MakeDetector() { return ToyLoopDetector(11, DetectorOptions()); }

Eigen::Isometry3d At(double x, double y, double z) {
  Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
  pose.translation() = Eigen::Vector3d(x, y, z);
  return pose;
}

map::Keyframe MakeKeyframe(std::int64_t id, double time, const StereoWorld& world,
                           const Eigen::Isometry3d& true_pose, const Eigen::Isometry3d& odometry,
                           bool starts_new_segment = false) {
  map::Keyframe keyframe;
  keyframe.id = id;
  keyframe.timestamp = time;
  keyframe.T_world_camera = odometry;
  keyframe.starts_new_segment = starts_new_segment;
  keyframe.features = Observe(world, true_pose);
  keyframe.map_point_ids.assign(keyframe.features.size(), -1);
  keyframe.place_descriptors = cv::Mat(50, 64, CV_8U);
  cv::RNG rng(static_cast<std::uint64_t>(100 + id));
  rng.fill(keyframe.place_descriptors, cv::RNG::UNIFORM, 0, 256);
  return keyframe;
}

const LoopCandidate* CandidateFor(const LoopDetection& detection, std::int64_t keyframe) {
  for (const LoopCandidate& candidate : detection.candidates) {
    if (candidate.keyframe_id == keyframe) return &candidate;
  }
  return nullptr;
}

// A poster: a plane of 80 points 3 m ahead of the camera that sees it, filling the top-left
// quarter of the image (4 of the 16 spread cells).
std::vector<Eigen::Vector3d> Poster(const Eigen::Vector3d& origin) {
  std::vector<Eigen::Vector3d> points;
  for (int row = 0; row < 8; ++row) {
    for (int col = 0; col < 10; ++col) {
      // u from ~30 to ~330 px, v from ~30 to ~200 px at 3 m depth.
      points.push_back(origin + Eigen::Vector3d(-2.3 + 0.22 * col, -1.37 + 0.16 * row, 3.0));
    }
  }
  return points;
}

// Places A (origin) and B (20 m along x) each with its own surroundings, and the same poster
// (same descriptors, same geometry) in view at both.
StereoWorld PosterWorld() {
  StereoWorld world;
  const std::vector<Eigen::Vector3d> poster_a = Poster(Eigen::Vector3d::Zero());
  const int first = world.Add(poster_a, 1);
  const cv::Mat poster_descriptors =
      world.descriptors.rowRange(first, first + static_cast<int>(poster_a.size())).clone();
  world.Add(RandomPoints(200, 2), 3);  // A's surroundings
  std::vector<Eigen::Vector3d> poster_b = Poster(Eigen::Vector3d(20, 0, 0));
  world.Add(poster_b, poster_descriptors);
  std::vector<Eigen::Vector3d> surroundings_b = RandomPoints(200, 4);
  for (Eigen::Vector3d& p : surroundings_b) p.x() += 20;
  world.Add(surroundings_b, 5);
  return world;
}

// The keyframe's map point ids: each key point's world point (the nearest to where its stereo
// point puts it, seen from `true_pose`) plus `offset` (a second pass makes new points).
void NameMapPoints(const StereoWorld& world, const Eigen::Isometry3d& true_pose,
                   std::int64_t offset, map::Keyframe* keyframe) {
  for (std::size_t k = 0; k < keyframe->map_point_ids.size(); ++k) {
    const Eigen::Vector3d point = true_pose * keyframe->features.points[k];
    std::size_t nearest = 0;
    for (std::size_t i = 1; i < world.points.size(); ++i) {
      if ((world.points[i] - point).norm() < (world.points[nearest] - point).norm()) nearest = i;
    }
    keyframe->map_point_ids[k] = offset + static_cast<std::int64_t>(nearest);
  }
}

TEST(LoopDetector, TrueRevisitIsAcceptedWithItsRelativePose) {
  const StereoWorld world = PosterWorld();
  place_recognition::LoopDetector detector = MakeDetector();
  map::Keyframe first_view = MakeKeyframe(0, 0.0, world, At(0, 0, 0), At(0, 0, 0));
  NameMapPoints(world, At(0, 0, 0), 0, &first_view);
  detector.Process(first_view);
  detector.Process(MakeKeyframe(1, 10.0, world, At(20, 0, 0), At(20, 0, 0)));
  // Back at A, 10 cm beside the first view; the odometry has drifted 15 cm over the 40 m.
  map::Keyframe revisit = MakeKeyframe(2, 20.0, world, At(0.1, 0, 0), At(0.25, 0, 0));
  NameMapPoints(world, At(0.1, 0, 0), 10000, &revisit);
  const LoopDetection detection = detector.Process(revisit);
  const LoopCandidate* a = CandidateFor(detection, 0);
  ASSERT_NE(a, nullptr);
  EXPECT_TRUE(a->accepted) << a->reason;
  ASSERT_TRUE(detection.loop.has_value());
  EXPECT_EQ(detection.loop->match_id, 0);
  EXPECT_EQ(detection.loop->query_id, 2);
  // Exact features: the relative pose is the true one to well under a millimetre.
  EXPECT_LT((detection.loop->T_match_query.translation() - Eigen::Vector3d(0.1, 0, 0)).norm(),
            1e-3);
  EXPECT_GE(detection.loop->inliers, 200);
  // Every inlier is a map point in both keyframes here: each pair is one world point, named on
  // the second pass (10000 + i) and on the first (i).
  EXPECT_EQ(detection.loop->shared_points.size(),
            static_cast<std::size_t>(detection.loop->inliers));
  for (const auto& [query_point, match_point] : detection.loop->shared_points) {
    EXPECT_EQ(query_point, match_point + 10000);
  }
}

// Two earlier views of A, both good loops (and B, whose posters make it a candidate that fails):
// candidates are verified best posterior first until one is accepted, and those after it are
// not verified at all (verification is most of a detection's time).
TEST(LoopDetector, CandidatesAfterAnAcceptedOneAreNotVerified) {
  const StereoWorld world = PosterWorld();
  place_recognition::LoopDetector detector = MakeDetector();
  detector.Process(MakeKeyframe(0, 0.0, world, At(0, 0, 0), At(0, 0, 0)));
  detector.Process(MakeKeyframe(1, 1.0, world, At(0.05, 0, 0), At(0.05, 0, 0)));
  detector.Process(MakeKeyframe(2, 10.0, world, At(20, 0, 0), At(20, 0, 0)));
  const LoopDetection detection =
      detector.Process(MakeKeyframe(3, 20.0, world, At(0.1, 0, 0), At(0.25, 0, 0)));
  ASSERT_TRUE(detection.loop.has_value());
  const auto accepted = std::find_if(detection.candidates.begin(), detection.candidates.end(),
                                     [](const LoopCandidate& c) { return c.accepted; });
  ASSERT_NE(accepted, detection.candidates.end());
  EXPECT_TRUE(accepted->keyframe_id == 0 || accepted->keyframe_id == 1) << accepted->keyframe_id;
  EXPECT_EQ(detection.loop->match_id, accepted->keyframe_id);
  for (auto c = detection.candidates.begin(); c != accepted; ++c) {
    EXPECT_TRUE(c->verified && !c->accepted) << c->keyframe_id << ": " << c->reason;
  }
  ASSERT_NE(accepted + 1, detection.candidates.end()) << "the other view of A is a candidate";
  for (auto c = accepted + 1; c != detection.candidates.end(); ++c) {
    EXPECT_FALSE(c->verified) << c->keyframe_id;
    EXPECT_FALSE(c->accepted) << c->keyframe_id;
    EXPECT_NE(c->reason.find("not verified"), std::string::npos) << c->reason;
    EXPECT_LE(c->probability, accepted->probability);
  }
}

// A room repeated exactly 20 m further on (the same objects in the same layout, as in an office
// building's identical floors): a view at B matches A over the whole image.
StereoWorld RepeatedRoomWorld() {
  StereoWorld world;
  std::vector<Eigen::Vector3d> room = RandomPoints(250, 2);
  const int first = world.Add(room, 3);
  const cv::Mat room_descriptors =
      world.descriptors.rowRange(first, first + static_cast<int>(room.size())).clone();
  for (Eigen::Vector3d& p : room) p.x() += 20;
  world.Add(room, room_descriptors);
  return world;
}

TEST(LoopDetector, RepeatedRoomWithinASegmentIsRejectedByTheOdometry) {
  const StereoWorld world = RepeatedRoomWorld();
  place_recognition::LoopDetector detector = MakeDetector();
  detector.Process(MakeKeyframe(0, 0.0, world, At(0, 0, 0), At(0, 0, 0)));
  // At B the view is identical to A's; the odometry says 20 m lie between them (5 cm drift).
  const LoopDetection detection =
      detector.Process(MakeKeyframe(1, 10.0, world, At(20, 0, 0), At(20.05, 0, 0)));
  const LoopCandidate* a = CandidateFor(detection, 0);
  ASSERT_NE(a, nullptr);
  EXPECT_GE(a->inliers, 200);  // geometrically perfect: only the odometry can tell
  EXPECT_FALSE(a->accepted);
  EXPECT_NE(a->reason.find("disagrees with the odometry"), std::string::npos) << a->reason;
  EXPECT_FALSE(detection.loop.has_value());
}

// After a tracking loss the odometry of the new segment says nothing about the old one, but its
// last loop does: a look-alike room of the old segment 20 m from where that loop put the camera
// is refused through the loop, even when FAB-MAP ranks it first (its place words are the
// query's) and it verifies perfectly; without the check (loop_consistency_path 0) it is taken.
TEST(LoopDetector, RepeatedRoomAcrossSegmentsIsRejectedThroughTheSegmentsLastLoop) {
  const StereoWorld world = RepeatedRoomWorld();
  for (const double consistency_path : {3.0, 0.0}) {
    SCOPED_TRACE("loop_consistency_path " + std::to_string(consistency_path));
    place_recognition::LoopDetectorOptions options = DetectorOptions();
    options.loop_consistency_path = consistency_path;
    place_recognition::LoopDetector detector = ToyLoopDetector(11, options);
    detector.Process(MakeKeyframe(0, 0.0, world, At(0, 0, 0), At(0, 0, 0)));
    const map::Keyframe at_b = MakeKeyframe(1, 10.0, world, At(20, 0, 0), At(20.05, 0, 0));
    detector.Process(at_b);
    // Tracking lost; back at A in a new segment (its own odom frame). Only keyframe 0 is old
    // enough: a true loop, the segment's first.
    const LoopDetection first = detector.Process(
        MakeKeyframe(2, 12.0, world, At(0.1, 0, 0), At(5, 5, 0), /*starts_new_segment=*/true));
    ASSERT_TRUE(first.loop.has_value());
    ASSERT_EQ(first.loop->match_id, 0);
    // 0.2 m further on in the new segment; the room at B looks the same to FAB-MAP and to PnP.
    map::Keyframe query = MakeKeyframe(3, 20.0, world, At(0.3, 0, 0), At(5.2, 5, 0));
    query.place_descriptors = at_b.place_descriptors.clone();
    const LoopDetection detection = detector.Process(query);
    const LoopCandidate* b = CandidateFor(detection, 1);
    ASSERT_NE(b, nullptr);
    ASSERT_TRUE(b->verified);
    EXPECT_GE(b->inliers, 200);  // geometrically perfect
    ASSERT_TRUE(detection.loop.has_value());
    if (consistency_path > 0) {
      EXPECT_FALSE(b->accepted);
      EXPECT_NE(b->reason.find("through the loop 2 -> 0"), std::string::npos) << b->reason;
      EXPECT_EQ(detection.loop->match_id, 0);
    } else {
      EXPECT_TRUE(b->accepted) << b->reason;
      EXPECT_EQ(detection.loop->match_id, 1);
    }
  }
}

TEST(LoopDetector, RepeatedPosterAcrossSegmentsIsRejectedByItsSpread) {
  const StereoWorld world = PosterWorld();
  place_recognition::LoopDetector detector = MakeDetector();
  detector.Process(MakeKeyframe(0, 0.0, world, At(0, 0, 0), At(0, 0, 0)));
  // Tracking was lost on the way: no odometry relates B to A.
  const LoopDetection detection = detector.Process(
      MakeKeyframe(1, 10.0, world, At(20, 0, 0), At(0, 0, 0), /*starts_new_segment=*/true));
  const LoopCandidate* a = CandidateFor(detection, 0);
  ASSERT_NE(a, nullptr);
  EXPECT_FALSE(a->accepted);
  EXPECT_NE(a->reason.find("image cells"), std::string::npos) << a->reason;
  EXPECT_FALSE(detection.loop.has_value());
}

TEST(LoopDetector, RecentKeyframesAreNoCandidates) {
  const StereoWorld world = PosterWorld();
  place_recognition::LoopDetector detector = MakeDetector();
  detector.Process(MakeKeyframe(0, 0.0, world, At(0, 0, 0), At(0, 0, 0)));
  // 2 s later at the same place: within min_age (5 s), not a loop.
  const LoopDetection detection =
      detector.Process(MakeKeyframe(1, 2.0, world, At(0.1, 0, 0), At(0.1, 0, 0)));
  EXPECT_TRUE(detection.candidates.empty());
}

// Views whose words tell places apart: a vocabulary of 64 words, and each place 20 random
// descriptors of its own (two places share about 20 x 20 / 64 of their words by chance).
cv::Mat RandomDescriptors(int rows, std::uint64_t seed) {
  cv::Mat descriptors(rows, 64, CV_8U);
  cv::RNG rng(seed);
  rng.fill(descriptors, cv::RNG::UNIFORM, 0, 256);
  return descriptors;
}

place_recognition::LoopDetector DetectorWithDistinctPlaces(
    const place_recognition::LoopDetectorOptions& options) {
  place_recognition::VocabularyOptions vocabulary_options;
  vocabulary_options.branching = 8;
  vocabulary_options.depth = 2;
  place_recognition::Vocabulary vocabulary =
      place_recognition::Vocabulary::Train(RandomDescriptors(1600, 3), vocabulary_options);
  std::vector<std::vector<int>> word_sets;
  for (int image = 0; image < 60; ++image) {
    word_sets.push_back(vocabulary.WordSet(RandomDescriptors(20, 1000 + image)));
  }
  place_recognition::FabMap fabmap(
      place_recognition::ChowLiuTree::Train(word_sets, vocabulary.size()),
      place_recognition::FabMapOptions());
  return place_recognition::LoopDetector(options, std::move(vocabulary), std::move(fabmap),
                                         kTestCamera, cv::NORM_HAMMING, 60.0);
}

// A corridor walked twice: places 0-7, then views of places 2, 3 and 4 again, then a view at
// place 5 that shows place 7's words (a poster hung at both). Alone, the look-alike is the best
// candidate; in a sequence, the run of revisits places it (to within the chain's step: its own
// words cannot say where in the run it is); a new odometry segment starts its chain afresh, and
// the look-alike is the best again.
TEST(LoopDetector, ASequenceOfKeyframesOutranksALookAlike) {
  const StereoWorld world = PosterWorld();
  const auto keyframe = [&](std::int64_t id, double time, std::uint64_t place, bool new_segment) {
    map::Keyframe frame = MakeKeyframe(id, time, world, At(0, 0, 0), At(0, 0, 0), new_segment);
    frame.place_descriptors = RandomDescriptors(20, 100 + place);
    return frame;
  };
  place_recognition::LoopDetectorOptions options;
  options.min_age = 5.0;
  options.min_probability = 0.0;
  options.min_log_odds = -std::numeric_limits<double>::infinity();
  options.max_candidates = 3;
  options.sequence_max_step = 1;  // these places are a location each, not frames a metre apart
  for (const bool new_segment : {false, true}) {
    for (const int length : {1, 3}) {
      SCOPED_TRACE("sequence of " + std::to_string(length) +
                   (new_segment ? ", the look-alike in a new segment" : ""));
      options.sequence_length = length;
      place_recognition::LoopDetector detector = DetectorWithDistinctPlaces(options);
      for (int place = 0; place < 8; ++place)
        detector.Process(keyframe(place, place, place, false));
      for (int k = 0; k < 3; ++k) detector.Process(keyframe(8 + k, 20 + k, 2 + k, false));
      const LoopDetection detection = detector.Process(keyframe(11, 23, 7, new_segment));
      ASSERT_FALSE(detection.candidates.empty());
      const std::int64_t best = detection.candidates.front().keyframe_id;
      if (length == 1 || new_segment) {
        EXPECT_EQ(best, 7);
      } else {
        // Its own words say nothing of place 5: the chain ends within a step of the run's
        // last place, 4.
        EXPECT_NEAR(best, 4, 1);
      }
    }
  }
}

TEST(LoopDetector, PlaceDescriptorsOfAnotherTypeAreRefused) {
  const StereoWorld world = PosterWorld();
  place_recognition::LoopDetector detector = MakeDetector();
  map::Keyframe keyframe = MakeKeyframe(0, 0.0, world, At(0, 0, 0), At(0, 0, 0));
  keyframe.place_descriptors = cv::Mat(50, 32, CV_32F, cv::Scalar(0.5f));  // float, 128 bytes
  try {
    detector.Process(keyframe);
    FAIL() << "float descriptors accepted by a binary vocabulary";
  } catch (const std::invalid_argument& error) {
    EXPECT_NE(std::string(error.what()).find("vocabulary"), std::string::npos) << error.what();
  }
}

}  // namespace
}  // namespace stereo_fabmap_slam::test
