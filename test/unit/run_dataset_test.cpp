// The offline runner on real data, run as a user runs it: a regression guard on accuracy and
// on determinism (the same input gives the same output, byte for byte).
#include <cmath>
#include <cstdio>
#include <map>
#include <string>

#include <gtest/gtest.h>

#include "stereo_fabmap_slam/camera/stereo_rectifier.h"
#include "stereo_fabmap_slam/datasets/euroc_sequence.h"
#include "stereo_fabmap_slam/dense/dense_options.h"
#include "stereo_fabmap_slam/dense/ply_files.h"
#include "stereo_fabmap_slam/io/trajectory_file.h"
#include "test_support.h"

namespace stereo_fabmap_slam::test {
namespace {

TEST(RunDataset, Mh01IsTrackedAccuratelyAndDeterministically) {
  const std::string asl = EurocSequencePath("MH01_first10s");
  TemporaryDirectory temp;
  std::string output;
  for (const std::string run : {"a", "b"}) {
    ASSERT_EQ(RunCommand(std::string(RUN_DATASET_BIN) + " " + asl + " --quiet --output " +
                             temp.path() + "/" + run + " 2>&1",
                         &output),
              0)
        << output;
  }
  const std::string summary = ReadTextFile(temp.path() + "/a/summary.json");
  RecordProperty("summary", summary);
  EXPECT_EQ(JsonNumber(summary, "frames"), 200);
  EXPECT_EQ(JsonNumber(summary, "frames_tracked"), 200);
  EXPECT_GT(JsonNumber(summary, "keyframes"), 5);
  // The target is 0.5 cm (docs/benchmarks.md); this guard is looser so that a change that
  // merely shifts the result within noise does not fail, while a real regression does.
  EXPECT_LT(JsonNumber(summary, "ate_rmse"), 0.01);
  EXPECT_EQ(JsonNumber(summary, "ate_matched"), 200);

  const std::string trajectory = ReadTextFile(temp.path() + "/a/trajectory.txt");
  EXPECT_EQ(trajectory, ReadTextFile(temp.path() + "/b/trajectory.txt"));
  EXPECT_EQ(ReadTextFile(temp.path() + "/a/keyframes.txt"),
            ReadTextFile(temp.path() + "/b/keyframes.txt"));
  EXPECT_EQ(io::ReadTumTrajectory(temp.path() + "/a/trajectory.txt").size(), 200u);
  // timing.csv: a header and a line per frame.
  const std::string timing = ReadTextFile(temp.path() + "/a/timing.csv");
  EXPECT_EQ(std::count(timing.begin(), timing.end(), '\n'), 201);
  EXPECT_EQ(
      timing.rfind("frame,timestamp,state,keyframe,rectification_ms,detection_ms,description_ms,"
                   "stereo_ms,tracking_ms,bundle_adjustment_ms",
                   0),
      0u);
}

TEST(RunDataset, Mh01SeenAtAQuarterOfItsRateIsTrackedWithoutALoss) {
  // Every 4th pair (5 Hz) is what a tracker that keeps up with a quarter of the pairs sees, e.g.
  // of a bag played at 4x. MH01 then turns by up to 10 degrees between frames (ground truth),
  // where the motion model mispredicts: before the tracker matched by descriptor when its
  // prediction found too little, 6 of these 50 frames were lost (issue 14); now none is. The
  // ATE stays within 2x the 1x run's guard above (measured 0.52 cm against 0.44 cm at 1x; 0.39
  // against 0.41 cm since the keyframe ratio counts only settled points).
  const std::string asl = EurocSequencePath("MH01_first10s");
  TemporaryDirectory temp;
  std::string output;
  ASSERT_EQ(RunCommand(std::string(RUN_DATASET_BIN) + " " + asl +
                           " --every 4 --no-loop-closing --quiet --output " + temp.path() + " 2>&1",
                       &output),
            0)
      << output;
  const std::string summary = ReadTextFile(temp.path() + "/summary.json");
  RecordProperty("summary", summary);
  EXPECT_EQ(JsonNumber(summary, "frames"), 50);
  EXPECT_EQ(JsonNumber(summary, "every"), 4);
  EXPECT_EQ(JsonNumber(summary, "frames_tracked"), 50);
  const std::string timing = ReadTextFile(temp.path() + "/timing.csv");
  EXPECT_EQ(timing.find(",lost,"), std::string::npos) << timing;
  EXPECT_LT(JsonNumber(summary, "ate_rmse"), 0.02);
  EXPECT_EQ(JsonNumber(summary, "ate_matched"), 50);
}

TEST(RunDataset, Mh01SeenAtLowerRatesKeepsTheKeyframesOfAFullRateRun) {
  // A tracker that skips frames takes a keyframe before a bound is crossed in the frames it will
  // skip, not at the first frame after (KeyframePolicyInput::before_next_frame), and the ratio
  // rule counts only points older than the last keyframe, whose number does not depend on how
  // soon after the keyframe the next frame is tracked. Measured keyframes at every 1st, 2nd,
  // 3rd, 4th pair: 26, 30, 30, 26 (before: 30, 26, 23, 19); on rendered routes (figure eight
  // seed 2, loops seed 3) 143/155/180/191 and 123/144/172/164 (before: 144/136/119/119 and
  // 123/107/102/86). Every 2nd and 3rd pair are what the nodelet sees of a bag played at 5x
  // (FrameQueue's catch_up_gap of 0.1 s); every 2.5th alternates the two skips, as a tracker at
  // 25 ms a pair does at 5x (33 keyframes measured; 152 and 136 on the rendered routes). The
  // runs are deterministic (the test above).
  const std::string asl = EurocSequencePath("MH01_first10s");
  TemporaryDirectory temp;
  std::string output;
  std::map<std::string, double> keyframes;
  for (const std::string every : {"1", "2", "2.5", "3"}) {
    const std::string directory = temp.path() + "/every" + every;
    ASSERT_EQ(RunCommand(std::string(RUN_DATASET_BIN) + " " + asl + " --every " + every +
                             " --no-loop-closing --quiet --output " + directory + " 2>&1",
                         &output),
              0)
        << output;
    const std::string summary = ReadTextFile(directory + "/summary.json");
    RecordProperty("summary_every" + every, summary);
    keyframes[every] = JsonNumber(summary, "keyframes");
    // One piece of odometry: the map started once. (At every 3rd pair one frame over the
    // pallets, where the camera passes close over blurred, repetitive texture, is lost with the
    // map kept and found again at the next; before the change that frame was tracked with 26
    // inliers: the stretch is at the edge at any policy.)
    const std::string timing = ReadTextFile(directory + "/timing.csv");
    std::size_t starts = 0;
    for (std::size_t at = timing.find("map started"); at != std::string::npos;
         at = timing.find("map started", at + 1)) {
      ++starts;
    }
    EXPECT_EQ(starts, 1u) << every << "\n" << timing;
    // As in the quarter-rate test: within 2x the 1x run's guard (measured 0.41-0.49 cm).
    EXPECT_LT(JsonNumber(summary, "ate_rmse"), 0.02) << every;
  }
  EXPECT_GE(keyframes["2"], keyframes["1"]);
  EXPECT_GE(keyframes["2.5"], keyframes["1"]);
  EXPECT_GE(keyframes["3"], keyframes["1"]);
}

TEST(RunDataset, Mh01MapSavedLoadedAndUsedForLocalization) {
  // Map MH01_first10s, save the map, then run the sequence again in localization mode on it:
  // the camera must be found on its first frame, follow the map's frame closely, and add nothing.
  const std::string asl = EurocSequencePath("MH01_first10s");
  TemporaryDirectory temp;
  const std::string map = temp.path() + "/mh01.map";
  std::string output;
  ASSERT_EQ(RunCommand(std::string(RUN_DATASET_BIN) + " " + asl + " --quiet --save-map " + map +
                           " --output " + temp.path() + "/mapping 2>&1",
                       &output),
            0)
      << output;
  ASSERT_EQ(RunCommand(std::string(RUN_DATASET_BIN) + " " + asl + " --quiet --load-map " + map +
                           " --mode localization --output " + temp.path() + "/localization 2>&1",
                       &output),
            0)
      << output;
  const std::string mapping = ReadTextFile(temp.path() + "/mapping/summary.json");
  const std::string summary = ReadTextFile(temp.path() + "/localization/summary.json");
  RecordProperty("summary", summary);
  EXPECT_EQ(JsonNumber(summary, "map_keyframes_loaded"), JsonNumber(mapping, "map_keyframes"));
  EXPECT_EQ(JsonNumber(summary, "map_keyframes"), JsonNumber(summary, "map_keyframes_loaded"));
  EXPECT_EQ(JsonNumber(summary, "frames_lost"), 0);  // relocalized on the first frame
  EXPECT_EQ(JsonNumber(summary, "trajectory_frames"), 200);
  EXPECT_GE(JsonNumber(summary, "relocalizations"), 1);
  // The target (measured 0.47 cm, the mapping run's own 0.44 cm).
  EXPECT_LT(JsonNumber(summary, "ate_rmse"), 0.01);
  // In the map's frame, without any alignment: where the mapping run put the camera (measured
  // 0.7 mm RMS; the map's keyframes are 0.5 cm from ground truth, so 5 mm bounds a good fit).
  const io::Trajectory mapped = io::ReadTumTrajectory(temp.path() + "/mapping/trajectory.txt");
  const io::Trajectory localized =
      io::ReadTumTrajectory(temp.path() + "/localization/trajectory.txt");
  ASSERT_EQ(mapped.size(), localized.size());
  double squared = 0;
  for (std::size_t i = 0; i < mapped.size(); ++i) {
    squared += (mapped[i].pose.translation() - localized[i].pose.translation()).squaredNorm();
  }
  EXPECT_LT(std::sqrt(squared / mapped.size()), 0.005);

  // A map file that is damaged is refused with a message and a non-zero exit.
  std::string bytes = ReadTextFile(map);
  bytes[bytes.size() / 2] ^= 0x10;
  {
    std::FILE* file = std::fopen((temp.path() + "/damaged.map").c_str(), "wb");
    ASSERT_NE(file, nullptr);
    std::fwrite(bytes.data(), 1, bytes.size(), file);
    std::fclose(file);
  }
  EXPECT_EQ(RunCommand(std::string(RUN_DATASET_BIN) + " " + asl + " --quiet --load-map " +
                           temp.path() + "/damaged.map --output " + temp.path() + "/bad 2>&1",
                       &output),
            1);
  EXPECT_NE(output.find("checksum"), std::string::npos) << output;
}

TEST(RunDataset, Mh01DenseMapIsWrittenWhereTheKeyframesLooked) {
  const std::string asl = EurocSequencePath("MH01_first10s");
  TemporaryDirectory temp;
  std::string output;
  ASSERT_EQ(RunCommand(std::string(RUN_DATASET_BIN) + " " + asl + " --quiet --dense --output " +
                           temp.path() + " 2>&1",
                       &output),
            0)
      << output;
  const std::string summary = ReadTextFile(temp.path() + "/summary.json");
  RecordProperty("summary", summary);
  EXPECT_EQ(JsonNumber(summary, "dense_keyframes"), JsonNumber(summary, "map_keyframes"));
  const dense::Mesh mesh = dense::ReadMeshPly(temp.path() + "/mesh.ply");
  const dense::Cloud cloud = dense::ReadCloudPly(temp.path() + "/dense_cloud.ply");
  EXPECT_EQ(static_cast<double>(mesh.vertices.size()), JsonNumber(summary, "dense_mesh_vertices"));
  EXPECT_EQ(static_cast<double>(mesh.triangles.size()),
            JsonNumber(summary, "dense_mesh_triangles"));
  // A room a camera flew through for 10 s: tens of thousands of vertices at least (measured
  // 366,377 with 26 keyframes).
  EXPECT_GT(mesh.vertices.size(), 20000u);
  EXPECT_GT(cloud.points.size(), 20000u);
  EXPECT_EQ(mesh.grey.size(), mesh.vertices.size());

  // Every vertex is where some keyframe looked: in front of it, inside its image, no farther
  // than the depth limit plus the truncation band. A pose inverted or in the wrong frame puts
  // the surface behind the cameras or off their images.
  const datasets::EurocSequence sequence = datasets::EurocSequence::Open(asl);
  const geometry::StereoCamera camera =
      camera::StereoRectifier::FromCalibration(sequence.calibration()).camera();
  const io::Trajectory keyframes = io::ReadTumTrajectory(temp.path() + "/keyframes.txt");
  const dense::StereoDepthOptions depth_options;
  const dense::FusionOptions fusion_options;
  // Along the ray at the image's corner, depth max_depth is ~1.4 times as far.
  const double reach = 1.5 * depth_options.max_depth + fusion_options.truncation;
  std::size_t seen = 0;
  for (const Eigen::Vector3d& vertex : mesh.vertices) {
    for (const io::StampedPose& keyframe : keyframes) {
      const Eigen::Vector3d p = keyframe.pose.inverse() * vertex;
      if (p.z() <= 0 || p.norm() > reach) continue;
      const double u = camera.fx * p.x() / p.z() + camera.cx;
      const double v = camera.fy * p.y() / p.z() + camera.cy;
      // Half a voxel's projection beyond the border: a voxel centre may lie just outside.
      if (u > -2 && v > -2 && u < camera.size.width + 1 && v < camera.size.height + 1) {
        ++seen;
        break;
      }
    }
  }
  EXPECT_GT(static_cast<double>(seen), 0.999 * static_cast<double>(mesh.vertices.size()));
}

TEST(RunDataset, BadArguments) {
  std::string output;
  EXPECT_EQ(RunCommand(std::string(RUN_DATASET_BIN) + " 2>&1", &output), 2);
  EXPECT_EQ(RunCommand(std::string(RUN_DATASET_BIN) + " /nonexistent --every 0 2>&1", &output), 2);
  EXPECT_NE(output.find("--every is a number of pairs, 1 to"), std::string::npos) << output;
  EXPECT_EQ(RunCommand(std::string(RUN_DATASET_BIN) + " /nonexistent --quiet 2>&1", &output), 1);
  EXPECT_NE(output.find("not an EuRoC ASL folder"), std::string::npos) << output;
}

}  // namespace
}  // namespace stereo_fabmap_slam::test
