// Trajectory files as other systems write them (issue: evaluate_trajectory refused a real
// visual-inertial system's file that evo evaluates): what is accepted, what is refused with the
// file and line, and an ATE on repeated and unordered stamps against a value computed by hand.
#include <string>

#include <gtest/gtest.h>

#include "stereo_fabmap_slam/evaluation/trajectory_metrics.h"
#include "stereo_fabmap_slam/io/input_error.h"
#include "stereo_fabmap_slam/io/trajectory_file.h"
#include "test_support.h"

namespace stereo_fabmap_slam::test {
namespace {

using io::ReadTrajectory;
using io::TrajectoryFileNotes;

TEST(TrajectoryFiles, TumAsOtherToolsWriteIt) {
  TemporaryDirectory temp;
  const std::string path = temp.path() + "/other.txt";
  // CRLF, a '#' header, comments and blank lines between poses, exponents, extra columns, a
  // quaternion written to 4 digits (normalised on reading).
  WriteTextFile(path,
                "# timestamp tx ty tz qx qy qz qw\r\n"
                "1.0e0 1.5e-1 0 0 0 0 0 1 0.01 0.02\r\n"
                "\r\n"
                "# a comment between poses\r\n"
                "1.05 2E-1 0 0 0 0 0.7071 0.7071 0.01 0.02\r\n");
  TrajectoryFileNotes notes;
  const evaluation::Trajectory trajectory = ReadTrajectory(path, &notes);
  ASSERT_EQ(trajectory.size(), 2u);
  EXPECT_DOUBLE_EQ(trajectory[0].timestamp, 1.0);
  EXPECT_DOUBLE_EQ(trajectory[0].pose.translation().x(), 0.15);
  EXPECT_DOUBLE_EQ(trajectory[1].pose.translation().x(), 0.2);
  EXPECT_NEAR(Eigen::Quaterniond(trajectory[1].pose.linear()).norm(), 1.0, 1e-12);
  EXPECT_NEAR(Eigen::AngleAxisd(trajectory[1].pose.linear()).angle(), M_PI / 2, 1e-4);
  EXPECT_EQ(notes.repeated_stamps + notes.unordered_stamps, 0u);
  EXPECT_FALSE(notes.header_skipped);
}

TEST(TrajectoryFiles, EurocCsvWithHeaderRowAndMoreColumns) {
  TemporaryDirectory temp;
  const std::string path = temp.path() + "/estimate.csv";
  // A header row without '#', 10 columns, CRLF, a timestamp with an exponent.
  WriteTextFile(path,
                "timestamp,x,y,z,qw,qx,qy,qz,vx,vy\r\n"
                "1403636579763555584,1,2,3,1,0,0,0,0.5,0.5\r\n"
                "1.403636579813555e18,1,2,3.5,1,0,0,0,0.5,0.5\r\n");
  TrajectoryFileNotes notes;
  const evaluation::Trajectory trajectory = ReadTrajectory(path, &notes);
  EXPECT_TRUE(notes.header_skipped);
  ASSERT_EQ(trajectory.size(), 2u);
  EXPECT_NEAR(trajectory[0].timestamp, 1403636579.763555584, 1e-6);
  // The exponent form holds 16 digits: the stamp to within a microsecond.
  EXPECT_NEAR(trajectory[1].timestamp - trajectory[0].timestamp, 0.05, 1e-6);
  EXPECT_DOUBLE_EQ(trajectory[1].pose.translation().z(), 3.5);
}

TEST(TrajectoryFiles, RepeatedAndUnorderedStampsAreKeptAndCounted) {
  TemporaryDirectory temp;
  const std::string path = temp.path() + "/vio.txt";
  WriteTextFile(path,
                "1.0 0 0 0 0 0 0 1\n"
                "1.1 1 0 0 0 0 0 1\n"
                "1.1 2 0 0 0 0 0 1\n"   // repeated
                "1.05 3 0 0 0 0 0 1\n"  // earlier than the one before
                "1.2 4 0 0 0 0 0 1\n");
  TrajectoryFileNotes notes;
  const evaluation::Trajectory trajectory = ReadTrajectory(path, &notes);
  ASSERT_EQ(trajectory.size(), 5u);  // all kept, in file order
  EXPECT_DOUBLE_EQ(trajectory[3].pose.translation().x(), 3.0);
  EXPECT_EQ(notes.repeated_stamps, 1u);
  EXPECT_EQ(notes.unordered_stamps, 1u);
}

// Each refusal names the file and the line (1-based, counting comment and blank lines).
void ExpectRefusedAtLine(const std::string& path, const std::string& text, int line,
                         const std::string& reason) {
  WriteTextFile(path, text);
  try {
    ReadTrajectory(path);
    ADD_FAILURE() << "accepted: " << text;
  } catch (const io::InputError& error) {
    const std::string message = error.what();
    EXPECT_NE(message.find(path + ":" + std::to_string(line) + ":"), std::string::npos) << message;
    EXPECT_NE(message.find(reason), std::string::npos) << message;
  }
}

TEST(TrajectoryFiles, WhatCannotBeMeantIsRefusedWithFileAndLine) {
  TemporaryDirectory temp;
  const std::string tum = temp.path() + "/bad.txt", csv = temp.path() + "/bad.csv";
  const std::string good = "0 0 0 0 0 0 0 1\n";
  ExpectRefusedAtLine(tum, good + "# comment\n1 0 zero 0 0 0 0 1\n", 3, "expected a number");
  ExpectRefusedAtLine(tum, good + "1 0 0 0 0 0 0 0\n", 2, "quaternion of zero length");
  ExpectRefusedAtLine(tum, good + "\n1 nan 0 0 0 0 0 1\n", 3, "not a finite number");
  ExpectRefusedAtLine(tum, good + "1 0 0 0 0 0 1\n", 2, "found 7 fields");
  ExpectRefusedAtLine(csv, "1,0,0,0,1,0,0,0\n2,0,0,inf,1,0,0,0\n", 2, "not a finite number");
  ExpectRefusedAtLine(csv, "1,0,0,0,1,0,0,0\nx2,0,0,0,1,0,0,0\n", 2, "expected a number");
}

// Ground truth: a square of side 2 in the plane z = 0, one pose a second, its lines shuffled.
// Estimate: every ground-truth stamp twice, once 3 cm above the plane and once 3 cm below.
// Worked by hand: the centroids agree; the cross-covariance of the pairs is the ground truth's
// own (the +-3 cm cancel pair by pair), symmetric and positive, so Umeyama's rotation is the
// identity and its translation zero; every pose is then 3 cm off: ATE RMSE = mean = max = 0.03 m.
// The corners of a 2 m square, one per second, as TUM lines "t x y z 0 0 0 1" for the given
// seconds; z_offsets gives, per line of each second, how far above the corner the pose is.
std::string SquareCorners(const std::vector<int>& seconds, const std::vector<double>& z_offsets) {
  const double corners[4][2] = {{1, 1}, {-1, 1}, {-1, -1}, {1, -1}};
  std::string text;
  for (int i : seconds) {
    for (double z : z_offsets) {
      text += std::to_string(i) + " " + std::to_string(corners[i % 4][0]) + " " +
              std::to_string(corners[i % 4][1]) + " " + std::to_string(z) + " 0 0 0 1\n";
    }
  }
  return text;
}

// evo_ape associates the shorter trajectory into the longer (evo/core/sync.py,
// associate_trajectories): here the 4 ground-truth poses each take the first of the two
// estimated poses at their stamp.
TEST(TrajectoryFiles, AnEstimateLongerThanTheTruthIsAssociatedAsEvoDoes) {
  TemporaryDirectory temp;
  const std::string truth = temp.path() + "/truth.txt", estimate = temp.path() + "/est.txt";
  WriteTextFile(truth, SquareCorners({2, 0, 3, 1}, {0.0}));  // shuffled
  WriteTextFile(estimate, SquareCorners({0, 1, 2, 3}, {0.03, -0.03}));
  TrajectoryFileNotes truth_notes, estimate_notes;
  const evaluation::EvaluationResult result = evaluation::EvaluateTrajectory(
      ReadTrajectory(truth, &truth_notes), ReadTrajectory(estimate, &estimate_notes), {});
  EXPECT_EQ(truth_notes.unordered_stamps, 2u);  // 2 -> 0 and 3 -> 1
  EXPECT_EQ(estimate_notes.repeated_stamps, 4u);
  // By hand: 4 pairs, every estimate 3 cm above its corner; the SE(3) alignment moves the
  // estimate 3 cm down and leaves no error. Pairing each estimated pose instead would give 8
  // pairs, 3 cm above and below, and an ATE of 3 cm.
  EXPECT_EQ(result.matched, 4u);
  EXPECT_NEAR(result.ate.rmse, 0.0, 1e-9);
  EXPECT_NEAR(Eigen::AngleAxisd(result.alignment.rotation).angle(), 0.0, 1e-9);
  EXPECT_NEAR((result.alignment.translation - Eigen::Vector3d(0, 0, -0.03)).norm(), 0.0, 1e-9);
  // Pairs come in the truth's file order, as evo's.
  ASSERT_EQ(result.matched_reference.size(), 4u);
  EXPECT_EQ(result.matched_reference[0].timestamp, 2.0);
  EXPECT_EQ(result.matched_reference[3].timestamp, 1.0);
}

// The estimate shorter than the truth, as usual, with stamps repeated on both sides: each
// estimated pose is paired, and of two ground-truth poses with one stamp the first in the file.
TEST(TrajectoryFiles, AteOnRepeatedAndUnorderedStampsMatchesAHandComputation) {
  TemporaryDirectory temp;
  const std::string truth = temp.path() + "/truth.txt", estimate = temp.path() + "/est.txt";
  // Second 1 twice: first the true corner, then a pose 5 m away that must not be taken.
  WriteTextFile(truth, SquareCorners({3, 1, 0, 2}, {0.0}) + "1 5 5 0 0 0 0 1\n" +
                           SquareCorners({4, 5, 6}, {0.0}));
  WriteTextFile(estimate, SquareCorners({0, 1, 2}, {0.03, -0.03}));
  TrajectoryFileNotes truth_notes, estimate_notes;
  const evaluation::EvaluationResult result = evaluation::EvaluateTrajectory(
      ReadTrajectory(truth, &truth_notes), ReadTrajectory(estimate, &estimate_notes), {});
  EXPECT_EQ(truth_notes.repeated_stamps, 0u);   // the second 1 follows 2, so it decreases
  EXPECT_EQ(truth_notes.unordered_stamps, 3u);  // 3 -> 1, 1 -> 0 and 2 -> 1
  EXPECT_EQ(estimate_notes.repeated_stamps, 3u);
  // By hand: 6 pairs, 3 cm above and below three corners. The centroids and the cross-covariance
  // of the positions are those of the corners alone (the offsets cancel), so the alignment is the
  // identity and every pose is 3 cm off. Taking the 5 m pose for second 1 would give metres.
  EXPECT_EQ(result.matched, 6u);
  EXPECT_NEAR(result.ate.rmse, 0.03, 1e-9);
  EXPECT_NEAR(result.ate.max, 0.03, 1e-9);
  EXPECT_NEAR(Eigen::AngleAxisd(result.alignment.rotation).angle(), 0.0, 1e-9);
  EXPECT_NEAR(result.alignment.translation.norm(), 0.0, 1e-9);
}

}  // namespace
}  // namespace stereo_fabmap_slam::test
