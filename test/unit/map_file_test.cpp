// Map files: a saved map comes back exactly; a damaged file, a map of another vocabulary or
// another camera is refused with a message, and the running map stays as it was.
#include "stereo_fabmap_slam/map/map_file.h"

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iterator>

#include <gtest/gtest.h>

#include "file_mutations.h"
#include "saved_maps.h"
#include "stereo_fabmap_slam/geometry/relative_pose_error.h"
#include "stereo_fabmap_slam/io/input_error.h"
#include "stereo_fabmap_slam/pipeline/mapping_stage.h"
#include "stereo_fabmap_slam/pipeline/place_stage.h"
#include "stereo_world.h"
#include "test_support.h"
#include "toy_place_recognition.h"

namespace stereo_fabmap_slam::test {
namespace {

// The two stages that keep a map, composed as StereoSlam composes them.
struct TestMap {
  explicit TestMap(std::uint64_t vocabulary_seed)
      : mapping(backend::BundleAdjustmentOptions(), backend::PoseGraphOptions(),
                [] { return 0.0; }),
        place(ToyLoopDetector(vocabulary_seed), relocalization::RelocalizerOptions(),
              [] { return 0.0; }) {}

  void AddKeyframe(const map::Keyframe& keyframe) {
    place.AddKeyframe(keyframe, mapping.AddKeyframe(keyframe, kTestCamera));
  }
  map::SavedMap Save(const geometry::StereoCamera& camera) const {
    return place.Save(mapping, camera);
  }
  void Load(const map::SavedMap& saved, const geometry::StereoCamera& camera) {
    place.Load(saved, camera);
    mapping.Load(saved);
  }

  pipeline::MappingStage mapping;
  pipeline::PlaceStage place;
};

TestMap MakeMap(std::uint64_t vocabulary_seed, int keyframes) {
  TestMap map(vocabulary_seed);
  StereoWorld world;
  world.Add(RandomPoints(300, 3), 5);
  for (int i = 0; i < keyframes; ++i) {
    map::Keyframe keyframe;
    keyframe.id = i;
    keyframe.timestamp = 100.0 + 0.5 * i;
    keyframe.T_world_camera = Eigen::Translation3d(0.1 * i, 0.0, 0.02 * i) *
                              Eigen::AngleAxisd(0.05 * i, Eigen::Vector3d::UnitY());
    keyframe.starts_new_segment = i == 3;  // two pieces of odometry
    keyframe.features = Observe(world, keyframe.T_world_camera);
    keyframe.map_point_ids.resize(keyframe.features.size());
    for (std::size_t k = 0; k < keyframe.map_point_ids.size(); ++k) {
      keyframe.map_point_ids[k] = k % 3 == 0 ? -1 : static_cast<std::int64_t>(1000 * i + k);
    }
    keyframe.place_descriptors = cv::Mat(40, 64, CV_8U);
    cv::RNG(static_cast<std::uint64_t>(50 + i))
        .fill(keyframe.place_descriptors, cv::RNG::UNIFORM, 0, 256);
    map.AddKeyframe(keyframe);
  }
  if (keyframes < 5) return map;
  // A relocalization edge joining the two pieces.
  map::LoopEdge edge;
  edge.match_id = 1;
  edge.query_id = 4;
  edge.T_match_query = Eigen::Translation3d(0.3, 0.0, 0.05) * Eigen::Isometry3d::Identity();
  edge.information = geometry::DiagonalPoseInformation(0.02, 0.2);
  map.mapping.AddEdge(edge, backend::PoseGraphEdgeType::kRelocalization);
  return map;
}

std::vector<char> ReadBytes(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  return std::vector<char>(std::istreambuf_iterator<char>(in), {});
}

void WriteBytes(const std::string& path, const std::vector<char>& bytes) {
  std::ofstream(path, std::ios::binary)
      .write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
}

TEST(MapFile, RoundTripsExactlyThroughAFileAndIntoAnotherMap) {
  TemporaryDirectory temp;
  const std::string path = temp.path() + "/map.bin";
  const TestMap original = MakeMap(7, 6);
  const map::SavedMap saved = original.Save(kTestCamera);
  ASSERT_EQ(saved.keyframes.size(), 6u);
  ASSERT_EQ(saved.edges.size(), 1u);
  map::SaveMapFile(path, saved);
  ExpectSameMaps(saved, map::LoadMapFile(path));

  // Loaded into a running map of the same vocabulary, it replaces that map: the same keyframes,
  // map poses, edges and pieces of odometry, so saving again gives the same map.
  TestMap other = MakeMap(7, 2);
  other.Load(map::LoadMapFile(path), kTestCamera);
  ExpectSameMaps(saved, other.Save(kTestCamera), 1e-12);
  EXPECT_TRUE(other.mapping.InMap(5));  // joined to the map by the relocalization edge
  EXPECT_EQ(other.place.detector().database().Get(4).segment, 1);
}

TEST(MapFile, DamagedFilesAreRefused) {
  TemporaryDirectory temp;
  const std::string path = temp.path() + "/map.bin";
  map::SaveMapFile(path, MakeMap(7, 6).Save(kTestCamera));
  const std::vector<char> bytes = ReadBytes(path);

  std::vector<char> flipped = bytes;
  flipped[flipped.size() / 2] ^= 0x10;
  WriteBytes(temp.path() + "/flipped.bin", flipped);
  EXPECT_THROW(map::LoadMapFile(temp.path() + "/flipped.bin"), io::InputError);

  WriteBytes(temp.path() + "/truncated.bin",
             std::vector<char>(bytes.begin(), bytes.begin() + bytes.size() * 2 / 3));
  EXPECT_THROW(map::LoadMapFile(temp.path() + "/truncated.bin"), io::InputError);

  EXPECT_THROW(map::LoadMapFile(temp.path() + "/missing.bin"), io::InputError);
}

// 3,000 mutants of a saved map (bit flips, truncations, appended bytes, and payload changes
// that pass the checksum): each refused with an InputError or loaded, none crashing, hanging or
// allocating more than 256 MB (the map itself is a few hundred kilobytes).
TEST(MapFile, FuzzedFilesAreRefusedOrLoadedNeverCrash) {
  TemporaryDirectory temp;
  const std::string path = temp.path() + "/map.bin";
  map::SaveMapFile(path, MakeMap(7, 6).Save(kTestCamera));
  const FuzzCounts counts =
      LoadMutants(path, 3000, 11, 256u << 20, [](const std::string& p) { map::LoadMapFile(p); });
  RecordProperty("refused", counts.refused);
  RecordProperty("loaded", counts.loaded);
  // At least every mutant whose checksum was not fixed (3 in 5); the map's payload is mostly
  // poses, points and descriptors, so many checksum-fixed changes are values a map may hold.
  EXPECT_GE(counts.refused, 1800);
}

TEST(MapFile, AMapOfAnotherVocabularyOrCameraIsRefusedAndTheRunningMapKept) {
  const map::SavedMap saved = MakeMap(7, 6).Save(kTestCamera);
  TestMap running = MakeMap(8, 2);  // another vocabulary
  const map::SavedMap before = running.Save(kTestCamera);
  try {
    running.Load(saved, kTestCamera);
    ADD_FAILURE() << "a map of another vocabulary was loaded";
  } catch (const io::InputError& error) {
    EXPECT_NE(std::string(error.what()).find("vocabulary"), std::string::npos) << error.what();
  }
  ExpectSameMaps(before, running.Save(kTestCamera), 1e-12);

  TestMap same_vocabulary = MakeMap(7, 2);
  const map::SavedMap kept = same_vocabulary.Save(kTestCamera);
  geometry::StereoCamera other_camera = kTestCamera;
  other_camera.baseline = 0.12;
  try {
    same_vocabulary.Load(saved, other_camera);
    ADD_FAILURE() << "a map of another camera was loaded";
  } catch (const io::InputError& error) {
    EXPECT_NE(std::string(error.what()).find("camera"), std::string::npos) << error.what();
  }
  ExpectSameMaps(kept, same_vocabulary.Save(kTestCamera), 1e-12);
}

}  // namespace
}  // namespace stereo_fabmap_slam::test
