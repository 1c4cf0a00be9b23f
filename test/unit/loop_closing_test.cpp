// Loop closing and relocalization in the offline runner, as a user runs them: rendered routes
// (make_synthetic_sequence, exact ground truth; the hall and the office) through run_dataset
// with the default vocabulary. On a route that returns to its start the revisit must be found,
// every accepted loop must join views that are really close, and closing must remove most of
// the drift; on the kidnap route the camera must be found again at once and the trajectory stay
// one piece.
#include <cmath>
#include <limits>
#include <string>
#include <utility>
#include <vector>

#include <gtest/gtest.h>

#include "stereo_fabmap_slam/io/csv_reader.h"
#include "stereo_fabmap_slam/io/trajectory_file.h"
#include "test_support.h"

namespace stereo_fabmap_slam::test {
namespace {

Eigen::Vector3d PositionAt(const io::Trajectory& truth, double time) {
  double best = std::numeric_limits<double>::max();
  Eigen::Vector3d position = Eigen::Vector3d::Zero();
  for (const auto& pose : truth) {
    if (std::abs(pose.timestamp - time) < best) {
      best = std::abs(pose.timestamp - time);
      position = pose.pose.translation();
    }
  }
  EXPECT_LT(best, 0.01) << "no ground truth near " << time;
  return position;
}

// Maps `seconds` of a rendered route (shared with the rostests, which play the same sequence
// through the nodelets) with run_dataset into temp/run, as a user would; returns its folder and
// summary.json (empty, and the test fails, if a program failed).
std::pair<std::string, std::string> MapRenderedRoute(const TemporaryDirectory& temp,
                                                     const std::string& route, int seconds,
                                                     int seed, const std::string& scene = "hall",
                                                     const std::string& options = "") {
  const std::string sequence = SharedSyntheticSequence(MAKE_SYNTHETIC_SEQUENCE_BIN, route, seconds,
                                                       seed, scene, scene == "hall");
  std::string output;
  if (sequence.empty() || RunCommand(std::string(RUN_DATASET_BIN) + " " + sequence + " --quiet " +
                                         options + " --output " + temp.path() + "/run 2>&1",
                                     &output) != 0) {
    ADD_FAILURE() << output;
    return {sequence, ""};
  }
  return {sequence, ReadTextFile(temp.path() + "/run/summary.json")};
}

// The loops run_dataset accepted (run/loops.csv), with how far apart the two keyframes'
// cameras were in ground truth (body frame: the rig is rigid, so camera and body distances
// differ by nothing here).
struct AcceptedLoop {
  std::string query_keyframe, match_keyframe;
  double query_time = 0, match_time = 0;  // [s] from the sequence's start
  double distance = 0;                    // [m]
};
std::vector<AcceptedLoop> AcceptedLoops(const std::string& sequence, const std::string& run) {
  const io::Trajectory truth =
      io::ReadEurocTrajectory(sequence + "/mav0/state_groundtruth_estimate0/data.csv");
  const std::string loops = run + "/loops.csv";
  EXPECT_EQ(ReadTextFile(loops).rfind("query_keyframe,query_time,match_keyframe,match_time,"
                                      "probability,inliers,accepted,reason\n",
                                      0),
            0u);
  std::vector<AcceptedLoop> accepted;
  for (const io::TextRow& row : io::ReadDelimitedText(loops, io::Separator::kComma)) {
    if (row.line_number == 1 || row.fields.size() < 8 || row.fields[6] != "1") continue;
    AcceptedLoop loop;
    loop.query_keyframe = row.fields[0];
    loop.match_keyframe = row.fields[2];
    const double query_time = std::stod(row.fields[1]), match_time = std::stod(row.fields[3]);
    loop.distance = (PositionAt(truth, query_time) - PositionAt(truth, match_time)).norm();
    loop.query_time = query_time - truth.front().timestamp;
    loop.match_time = match_time - truth.front().timestamp;
    accepted.push_back(loop);
  }
  return accepted;
}

TEST(LoopClosing, RenderedLoopIsClosedWithoutFalseLoops) {
  TemporaryDirectory temp;
  // 34 s of the "loop" route: one lap, back past the start from about 26 s on.
  const auto [sequence, summary] = MapRenderedRoute(temp, "loop", 34, 1);
  ASSERT_FALSE(summary.empty());
  RecordProperty("summary", summary);
  EXPECT_GE(JsonNumber(summary, "loops_accepted"), 1);
  // Measured 0.92 cm after closing against 3.87 cm of odometry (docs/benchmarks.md): the guard
  // asks for half the odometry's error, so that only a real regression fails.
  EXPECT_LT(JsonNumber(summary, "ate_rmse"), 0.5 * JsonNumber(summary, "ate_rmse_odometry"));
  EXPECT_LT(JsonNumber(summary, "ate_rmse"), 0.02);

  // Every accepted loop joins keyframes that were less than 1 m apart.
  const std::vector<AcceptedLoop> loops = AcceptedLoops(sequence, temp.path() + "/run");
  int after_revisit = 0;
  for (const AcceptedLoop& loop : loops) {
    EXPECT_LT(loop.distance, 1.0) << "loop " << loop.query_keyframe << " -> "
                                  << loop.match_keyframe;
    after_revisit += loop.query_time > 24.0 ? 1 : 0;
  }
  EXPECT_EQ(static_cast<double>(loops.size()), JsonNumber(summary, "loops_accepted"));
  EXPECT_GT(after_revisit, 0);
}

// The office floor (issue 32): corridors of plain walls and identical doors, posters and signs
// hung on several walls. 90 s of its loop: one lap of the outer corridors (80 s), then 10 s
// back along the first corridor. The revisit must be found, and no loop may join look-alike
// doors or posters of different corridors (keyframes > 1 m apart in ground truth: a true
// revisit passes within 0.15 m of an old keyframe, and corridors lie metres apart). The bound
// on the trajectory is the target: half the odometry's error (measured on these 90 s:
// 33 loops, none far, 7.81 cm against 26.2 cm; on the 170 s seed-11 route of
// docs/place_recognition.md 31 %).
TEST(LoopClosing, OfficeLoopIsClosedWithoutLoopsBetweenLookAlikeCorridors) {
  TemporaryDirectory temp;
  const auto [sequence, summary] = MapRenderedRoute(temp, "loop", 90, 21, "office");
  ASSERT_FALSE(summary.empty());
  RecordProperty("summary", summary);
  const std::vector<AcceptedLoop> loops = AcceptedLoops(sequence, temp.path() + "/run");
  int after_lap = 0;
  for (const AcceptedLoop& loop : loops) {
    EXPECT_LT(loop.distance, 1.0) << "loop " << loop.query_keyframe << " (" << loop.query_time
                                  << " s) -> " << loop.match_keyframe << " (" << loop.match_time
                                  << " s)";
    after_lap += loop.query_time > 80.0 && loop.match_time < 10.0 ? 1 : 0;
  }
  EXPECT_GE(after_lap, 1);
  EXPECT_LT(JsonNumber(summary, "ate_rmse"), 0.5 * JsonNumber(summary, "ate_rmse_odometry"));
}

// What the kidnap route's run must show: the camera found again at once after the jump and the
// trajectory one piece, within `max_ate` [m] of the truth.
void ExpectFoundAgainInOnePiece(const std::string& summary, double max_ate) {
  EXPECT_GE(JsonNumber(summary, "relocalization_attempts"), 1);
  // Found again within 1 s of the jump (20 frames): fewer frames than that off the map.
  EXPECT_LE(JsonNumber(summary, "frames_lost"), 20);
  // One piece: every frame in the map trajectory, evaluated with one alignment.
  EXPECT_EQ(JsonNumber(summary, "trajectory_frames"), JsonNumber(summary, "frames"));
  EXPECT_EQ(JsonNumber(summary, "ate_matched"), JsonNumber(summary, "frames"));
  // The odometry alone, two unrelated pieces, is metres off.
  EXPECT_LT(JsonNumber(summary, "ate_rmse"), max_ate);
  EXPECT_GT(JsonNumber(summary, "ate_rmse_odometry"), 1.0);
}

TEST(Relocalization, KidnappedCameraIsFoundAgainAndTheTrajectoryStaysOnePiece) {
  TemporaryDirectory temp;
  // The kidnap route: at 60 % of its 40 s the camera jumps back half a lap, to a place it saw
  // some 13 s before. Tracking fails on the jump; the odometry starts a new piece of map, which
  // a relocalization confirmed from 1.5 m on or, sooner, a loop from one of its keyframes joins
  // to the map (relocalization.confirm_distance; measured: a loop, one frame after the jump).
  const std::string summary = MapRenderedRoute(temp, "kidnap", 40, 2).second;
  ASSERT_FALSE(summary.empty());
  RecordProperty("summary", summary);
  // The target, 3 cm (measured 2.3 cm on these 40 s, 1.5 cm on 50 s).
  ExpectFoundAgainInOnePiece(summary, 0.03);
}

// run_dataset --threads: the keyframes mapped on a second thread while tracking goes on, as in
// the nodelet graph; the frame that asks for a relocalization after the jump waits for the
// keyframes before it. The driver's correctness, not the accuracy (the test above measures that
// in one thread, deterministically): found again at once, one piece, every keyframe in the map,
// every accepted loop true. Its trajectory depends on when the bundle adjustment's updates
// arrive: 1.40-1.49 cm here alone or beside two busy processes, 3.04 cm once in make test beside
// the nice-19 sanitizer build; the bound, 5 cm, still fails a segment placed wrongly (tens of cm)
// or left apart (metres). 4.8x real time against 3.6x in one thread.
TEST(Relocalization, KidnappedCameraIsFoundAgainWithTheMappingOnItsOwnThread) {
  TemporaryDirectory temp;
  const auto [sequence, summary] = MapRenderedRoute(temp, "kidnap", 40, 2, "hall", "--threads");
  ASSERT_FALSE(summary.empty());
  RecordProperty("summary", summary);
  ExpectFoundAgainInOnePiece(summary, 0.05);
  EXPECT_EQ(JsonNumber(summary, "map_keyframes"), JsonNumber(summary, "keyframes"));
  EXPECT_GE(JsonNumber(summary, "loops_accepted"), 1);
  for (const AcceptedLoop& loop : AcceptedLoops(sequence, temp.path() + "/run")) {
    EXPECT_LT(loop.distance, 1.0) << "loop " << loop.query_keyframe << " -> "
                                  << loop.match_keyframe;
  }
  // The keyframes' bundle adjustment times reached their frames' lines of timing.csv.
  EXPECT_GT(JsonNumber(summary, "bundle_adjustment_ms_mean"), 0.0);
}

}  // namespace
}  // namespace stereo_fabmap_slam::test
