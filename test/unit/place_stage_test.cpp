// The place stage's answers to questions from outside the pipeline (the detect_loop service):
// what it refuses and why, and that a keyframe asked to join becomes a place like the mapping
// stage's.
#include "stereo_fabmap_slam/pipeline/place_stage.h"

#include <gtest/gtest.h>

#include "stereo_fabmap_slam/pipeline/mapping_stage.h"
#include "stereo_world.h"
#include "toy_place_recognition.h"

namespace stereo_fabmap_slam::test {
namespace {

class PlaceStageQueries : public ::testing::Test {
 protected:
  PlaceStageQueries()
      : mapping_(backend::BundleAdjustmentOptions(), backend::PoseGraphOptions(),
                 [] { return 0.0; }),
        place_(ToyLoopDetector(3), relocalization::RelocalizerOptions(), [] { return 0.0; }) {
    world_.Add(RandomPoints(300, 3), 5);
  }

  map::Keyframe Keyframe(std::int64_t id) const {
    map::Keyframe keyframe;
    keyframe.id = id;
    keyframe.timestamp = 0.5 * id;
    keyframe.T_world_camera = Eigen::Isometry3d(Eigen::Translation3d(0.1 * id, 0, 0));
    keyframe.features = Observe(world_, keyframe.T_world_camera);
    keyframe.map_point_ids.assign(keyframe.features.size(), -1);
    keyframe.place_descriptors = cv::Mat(40, 64, CV_8U);
    cv::RNG(static_cast<std::uint64_t>(50 + id))
        .fill(keyframe.place_descriptors, cv::RNG::UNIFORM, 0, 256);
    return keyframe;
  }

  static pipeline::LoopQuery Stored(std::int64_t id) {
    pipeline::LoopQuery query;
    query.stored_id = id;
    return query;
  }

  StereoWorld world_;
  pipeline::MappingStage mapping_;
  pipeline::PlaceStage place_;
};

TEST_F(PlaceStageQueries, QuestionsItCannotAnswerAreRefusedWithTheReason) {
  // No stage made yet (the LoopDetector before its first keyframe): it holds nothing.
  EXPECT_EQ(pipeline::LoopQueryRefusal(Stored(3), nullptr), "keyframe 3 is not in the map");
  pipeline::LoopQuery bare;
  bare.keyframe.id = 9;
  EXPECT_EQ(pipeline::LoopQueryRefusal(bare, nullptr), "the keyframe has no descriptors");
  bare.keyframe = Keyframe(9);
  EXPECT_EQ(pipeline::LoopQueryRefusal(bare, nullptr), "");

  for (std::int64_t id = 0; id < 3; ++id) {
    const map::Keyframe keyframe = Keyframe(id);
    place_.AddKeyframe(keyframe, mapping_.AddKeyframe(keyframe, kTestCamera));
  }
  EXPECT_EQ(pipeline::LoopQueryRefusal(Stored(1), &place_), "");
  EXPECT_EQ(pipeline::LoopQueryRefusal(Stored(7), &place_), "keyframe 7 is not in the map");
  pipeline::LoopQuery again;
  again.keyframe = Keyframe(1);
  again.add = true;
  EXPECT_EQ(pipeline::LoopQueryRefusal(again, &place_), "keyframe 1 is in the map already");
  EXPECT_THROW(place_.Answer(again), std::invalid_argument);
  again.add = false;  // only asked: nothing joins, so nothing is in the way
  EXPECT_NO_THROW(place_.Answer(again));
  EXPECT_NO_THROW(place_.Answer(Stored(2)));
}

TEST_F(PlaceStageQueries, AKeyframeAskedToJoinBecomesAPlace) {
  const map::Keyframe first = Keyframe(0);
  place_.AddKeyframe(first, mapping_.AddKeyframe(first, kTestCamera));
  pipeline::LoopQuery join;
  join.keyframe = Keyframe(5);
  join.add = true;
  place_.Answer(join);
  EXPECT_TRUE(place_.detector().database().Contains(5));
  EXPECT_EQ(pipeline::LoopQueryRefusal(Stored(5), &place_), "");
  pipeline::LoopQuery asked;
  asked.keyframe = Keyframe(6);
  place_.Answer(asked);
  EXPECT_FALSE(place_.detector().database().Contains(6)) << "asked only";
}

}  // namespace
}  // namespace stereo_fabmap_slam::test
