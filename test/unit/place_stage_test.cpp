// The place stage's answers to questions from outside the pipeline (the detect_loop service):
// what it refuses and why, and that a keyframe asked to join becomes a place like the mapping
// stage's. And the place service the LoopDetector runs it through: a stage made with the first
// camera, start-up with a mode and map file that may be refused, map files, all said in words.
#include "stereo_fabmap_slam/pipeline/place_stage.h"

#include <filesystem>
#include <fstream>

#include <gtest/gtest.h>

#include "stereo_fabmap_slam/pipeline/mapping_stage.h"
#include "stereo_fabmap_slam/pipeline/place_service.h"
#include "stereo_world.h"
#include "test_support.h"
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

// A place service over the toy vocabulary; counts the stages it makes.
pipeline::PlaceService ToyPlaceService(int* stages_made) {
  return pipeline::PlaceService([stages_made](const geometry::StereoCamera&) {
    ++*stages_made;
    return pipeline::PlaceStage(ToyLoopDetector(3), relocalization::RelocalizerOptions(),
                                [] { return 0.0; });
  });
}

bool Contains(const std::vector<std::string>& texts, const std::string& part) {
  for (const std::string& text : texts) {
    if (text.find(part) != std::string::npos) return true;
  }
  return false;
}

TEST(PlaceService, ModesAreAskedForByName) {
  EXPECT_EQ(pipeline::ModeNamed("localization").mode, pipeline::SlamMode::kLocalization);
  EXPECT_EQ(pipeline::ModeNamed("localization").message, "mode localization");
  EXPECT_EQ(pipeline::ModeNamed("mapping").mode, pipeline::SlamMode::kMapping);
  const pipeline::ModeAnswer bogus = pipeline::ModeNamed("Mapping ");
  EXPECT_FALSE(bogus.mode.has_value());
  EXPECT_EQ(bogus.message, "unknown mode 'Mapping ' (mapping, localization)");
}

TEST_F(PlaceStageQueries, AServiceStartsEmptyAndMappingWhenItsModeOrMapIsRefused) {
  TemporaryDirectory temp;
  int stages = 0;
  pipeline::PlaceService service = ToyPlaceService(&stages);
  const pipeline::PlaceService::StartUp plain = service.Start("localization", "");
  EXPECT_EQ(plain.mode, pipeline::SlamMode::kLocalization);
  EXPECT_TRUE(plain.errors.empty());
  EXPECT_FALSE(plain.map.has_value());

  const pipeline::PlaceService::StartUp bogus = service.Start("bogus", "");
  EXPECT_EQ(bogus.mode, pipeline::SlamMode::kMapping);
  EXPECT_TRUE(Contains(bogus.errors, "~mode 'bogus' is not a mode (mapping, localization)"));

  // Localization in a map that is not there, or damaged: mapping afresh, and no stage made for a
  // map refused (the first keyframe's camera makes it).
  const std::string damaged = temp.path() + "/damaged.map";
  std::ofstream(damaged) << "not a map";
  for (const std::string& file : {temp.path() + "/missing.map", damaged}) {
    const pipeline::PlaceService::StartUp refused = service.Start("localization", file);
    EXPECT_EQ(refused.mode, pipeline::SlamMode::kMapping) << file;
    EXPECT_FALSE(refused.map.has_value());
    EXPECT_TRUE(Contains(refused.errors, "~map_file refused: ")) << file;
    EXPECT_TRUE(Contains(refused.errors, "running with an empty map in mapping mode"));
    EXPECT_TRUE(service.empty());
    EXPECT_EQ(service.stage(), nullptr);
  }
  EXPECT_EQ(stages, 0) << "a file refused before its vocabulary was read makes no stage";
  pipeline::RelocalizationRequest request;
  EXPECT_EQ(service.Relocalize(request, mapping_).result.status,
            relocalization::RelocalizationStatus::kEmptyMap);
  EXPECT_EQ(service.SaveMap(temp.path() + "/empty.map", mapping_).message, "the map is empty");
}

TEST_F(PlaceStageQueries, AServiceSavesAndLoadsMapsAndSaysWhatItsPlacesDoNotCover) {
  TemporaryDirectory temp;
  int stages = 0;
  pipeline::PlaceService service = ToyPlaceService(&stages);
  for (std::int64_t id = 0; id < 4; ++id) {
    const map::Keyframe keyframe = Keyframe(id);
    const pipeline::PlaceService::KeyframeOutcome outcome =
        service.Take(keyframe, kTestCamera, mapping_.AddKeyframe(keyframe, kTestCamera));
    EXPECT_TRUE(outcome.warnings.empty()) << "it saw the run from its first keyframe";
    ASSERT_TRUE(outcome.result.has_value()) << "in the map graph: a place, and its detection";
    EXPECT_EQ(outcome.result->keyframe_id, id);
  }
  EXPECT_EQ(stages, 1);
  const std::string path = temp.path() + "/four.map";
  const pipeline::MapFileAnswer saved = service.SaveMap(path, mapping_);
  EXPECT_TRUE(saved.success) << saved.message;
  EXPECT_EQ(saved.keyframes, 4u);
  EXPECT_EQ(saved.message, "saved 4 keyframes and 0 loop and relocalization edges to " + path);
  // Refused saves leave nothing behind (a 4 MB ".partial" beside a directory before).
  const pipeline::MapFileAnswer directory = service.SaveMap(temp.path(), mapping_);
  EXPECT_FALSE(directory.success) << "a directory is no file";
  EXPECT_NE(directory.message.find("is a directory"), std::string::npos) << directory.message;
  EXPECT_FALSE(std::filesystem::exists(temp.path() + ".partial"));
  const pipeline::MapFileAnswer unnamed = service.SaveMap("", mapping_);
  EXPECT_FALSE(unnamed.success);
  EXPECT_NE(unnamed.message.find("empty path"), std::string::npos) << unnamed.message;
  const std::string missing_folder = temp.path() + "/no/such/folder/four.map";
  EXPECT_FALSE(service.SaveMap(missing_folder, mapping_).success);
  EXPECT_FALSE(std::filesystem::exists(missing_folder + ".partial"));
  // A relative path is the working directory's, and the answer says where that is.
  const std::filesystem::path working = std::filesystem::current_path();
  std::filesystem::current_path(temp.path());
  const pipeline::MapFileAnswer relative = service.SaveMap("relative.map", mapping_);
  std::filesystem::current_path(working);
  EXPECT_TRUE(relative.success) << relative.message;
  EXPECT_NE(relative.message.find(" to " + temp.path() + "/relative.map"), std::string::npos)
      << relative.message;
  EXPECT_TRUE(std::filesystem::exists(temp.path() + "/relative.map"));

  // Started while the odometry ran: its first keyframe is 6.
  int restarted_stages = 0;
  pipeline::PlaceService restarted = ToyPlaceService(&restarted_stages);
  const map::Keyframe late = Keyframe(6);
  pipeline::MappingStage other_mapping(backend::BundleAdjustmentOptions(),
                                       backend::PoseGraphOptions(), [] { return 0.0; });
  EXPECT_TRUE(Contains(
      restarted.Take(late, kTestCamera, other_mapping.AddKeyframe(late, kTestCamera)).warnings,
      "first keyframe received is 6: the keyframes before it are not places"));
  // A keyframe whose own message never came: no place, and said so.
  const pipeline::PlaceService::KeyframeOutcome unseen =
      restarted.Take(other_mapping.AddKeyframe(Keyframe(7), kTestCamera));
  EXPECT_FALSE(unseen.result.has_value());
  EXPECT_TRUE(Contains(unseen.warnings,
                       "keyframe 7 joined the map, but its keyframe message "
                       "never arrived"));
  EXPECT_FALSE(restarted.stage()->detector().database().Contains(7));

  // Loaded into a service without a stage: made with the map's camera, numbered above it, and
  // the map as the mapping stage will rebuild it from the same file.
  int loaded_stages = 0;
  pipeline::PlaceService loading = ToyPlaceService(&loaded_stages);
  std::optional<pipeline::LoadedMapFile> loaded;
  const pipeline::MapFileAnswer answer = loading.LoadMap(path, &loaded);
  ASSERT_TRUE(answer.success) << answer.message;
  EXPECT_EQ(answer.message, "loaded 4 keyframes from " + path);
  ASSERT_TRUE(loaded.has_value());
  EXPECT_EQ(loaded->path, path);
  EXPECT_EQ(loaded->loaded.keyframes, 4u);
  EXPECT_EQ(loaded->loaded.next_keyframe_id, 4);
  EXPECT_EQ(loaded->saved.keyframes.size(), 4u);
  // Until the mapping stage says otherwise, relocalization and saves are about the file's map.
  const std::shared_ptr<const pipeline::MapSnapshot> followed = loading.followed_map();
  ASSERT_EQ(followed->keyframes.size(), 4u);
  for (std::int64_t id = 0; id < 4; ++id) {
    EXPECT_TRUE(followed->InMap(id));
    EXPECT_TRUE(followed->MapPose(id).isApprox(mapping_.MapPose(id), 1e-9)) << id;
  }
  EXPECT_EQ(loaded_stages, 1);
  // A file refused later leaves the loaded map as it was.
  std::optional<pipeline::LoadedMapFile> none;
  const pipeline::MapFileAnswer refused = loading.LoadMap(temp.path() + "/missing.map", &none);
  EXPECT_FALSE(refused.success);
  EXPECT_NE(refused.message.find("; the map is unchanged"), std::string::npos) << refused.message;
  EXPECT_FALSE(none.has_value());
  ASSERT_NE(loading.stage(), nullptr);
  EXPECT_TRUE(loading.stage()->detector().database().Contains(3));
  // The mapping stage's next word replaces it.
  auto graph = std::make_shared<pipeline::MapSnapshot>(*followed);
  graph->keyframes.erase(3);
  loading.FollowMap(graph);
  EXPECT_EQ(loading.followed_map()->keyframes.size(), 3u);
  // Loop queries go through the same checks as the stage's.
  EXPECT_THROW(restarted.Answer(Stored(2), kTestCamera), std::invalid_argument);
  EXPECT_NO_THROW(loading.Answer(Stored(2), kTestCamera));
}

}  // namespace
}  // namespace stereo_fabmap_slam::test
