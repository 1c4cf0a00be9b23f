#include <cmath>
#include <random>
#include <string>

#include <gtest/gtest.h>

#include "stereo_fabmap_slam/evaluation/association.h"
#include "stereo_fabmap_slam/evaluation/trajectory_metrics.h"
#include "stereo_fabmap_slam/io/input_error.h"
#include "stereo_fabmap_slam/io/trajectory_file.h"
#include "test_support.h"

namespace stereo_fabmap_slam::test {
namespace {

using namespace evaluation;  // NOLINT: the module under test
using namespace io;          // NOLINT: its trajectory files

Eigen::Isometry3d MakePose(double yaw, double pitch, double roll, const Eigen::Vector3d& t) {
  Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
  pose.linear() = (Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitZ()) *
                   Eigen::AngleAxisd(pitch, Eigen::Vector3d::UnitY()) *
                   Eigen::AngleAxisd(roll, Eigen::Vector3d::UnitX()))
                      .toRotationMatrix();
  pose.translation() = t;
  return pose;
}

// A 10 s helix with turning orientation, 20 Hz: non-degenerate for every alignment.
Trajectory Helix() {
  Trajectory trajectory;
  for (int i = 0; i < 200; ++i) {
    const double t = 0.05 * i;
    trajectory.push_back(
        {100.0 + t, MakePose(0.6 * t, 0.1 * std::sin(t), 0.05 * t,
                             {2.0 * std::cos(0.6 * t), 2.0 * std::sin(0.6 * t), 0.2 * t})});
  }
  return trajectory;
}

Trajectory Moved(const Trajectory& trajectory, const Similarity3& motion) {
  Trajectory moved;
  for (const StampedPose& p : trajectory) moved.push_back({p.timestamp, motion.Apply(p.pose)});
  return moved;
}

Similarity3 KnownMotion(double scale) {
  Similarity3 motion;
  motion.rotation = MakePose(0.7, -0.3, 1.1, Eigen::Vector3d::Zero()).linear();
  motion.translation = Eigen::Vector3d(3.0, -1.0, 0.5);
  motion.scale = scale;
  return motion;
}

Similarity3 Inverse(const Similarity3& s) {
  Similarity3 inverse;
  inverse.rotation = s.rotation.transpose();
  inverse.scale = 1.0 / s.scale;
  inverse.translation = -(inverse.scale * (inverse.rotation * s.translation));
  return inverse;
}

TEST(Alignment, RecoversAKnownSE3Motion) {
  const Trajectory reference = Helix();
  const Similarity3 motion = KnownMotion(1.0);
  // The estimate lives in a frame moved by the inverse motion; alignment must find `motion`.
  const Trajectory estimate = Moved(reference, Inverse(motion));
  EvaluationOptions options;
  const EvaluationResult result = EvaluateTrajectory(reference, estimate, options);
  EXPECT_EQ(result.matched, 200u);
  EXPECT_LT((result.alignment.rotation - motion.rotation).norm(), 1e-6);
  EXPECT_LT((result.alignment.translation - motion.translation).norm(), 1e-6);
  EXPECT_DOUBLE_EQ(result.alignment.scale, 1.0);
  EXPECT_LT(result.ate.rmse, 1e-9);
  EXPECT_LT(result.rpe.translation.rmse, 1e-9);
  // Without alignment the same estimate is metres off.
  options.alignment = AlignmentMode::kNone;
  EXPECT_GT(EvaluateTrajectory(reference, estimate, options).ate.rmse, 1.0);
}

TEST(Alignment, RecoversAKnownSim3Motion) {
  const Trajectory reference = Helix();
  const Similarity3 motion = KnownMotion(2.5);
  const Trajectory estimate = Moved(reference, Inverse(motion));
  EvaluationOptions options;
  options.alignment = AlignmentMode::kSim3;
  const EvaluationResult result = EvaluateTrajectory(reference, estimate, options);
  EXPECT_NEAR(result.alignment.scale, 2.5, 1e-6);
  EXPECT_LT((result.alignment.rotation - motion.rotation).norm(), 1e-6);
  EXPECT_LT((result.alignment.translation - motion.translation).norm(), 1e-6);
  EXPECT_LT(result.ate.rmse, 1e-9);
  // SE(3) alignment cannot absorb the scale: a clear residual error remains.
  options.alignment = AlignmentMode::kSE3;
  EXPECT_GT(EvaluateTrajectory(reference, estimate, options).ate.rmse, 0.3);
}

TEST(Alignment, NoisyEstimateGivesTheNoiseLevel) {
  const Trajectory reference = Helix();
  const Similarity3 motion = KnownMotion(1.0);
  Trajectory estimate = Moved(reference, Inverse(motion));
  std::mt19937 random(42);
  const double sigma = 0.01;  // 1 cm per axis
  std::normal_distribution<double> noise(0.0, sigma);
  for (StampedPose& p : estimate)
    p.pose.translation() += Eigen::Vector3d(noise(random), noise(random), noise(random));
  const EvaluationResult result = EvaluateTrajectory(reference, estimate, EvaluationOptions{});
  // 200 points spread over metres pin the rotation to about sigma / (sqrt(N) * 2 m) ~ 0.02 deg
  // and the translation to about sigma / sqrt(N) ~ 0.7 mm; allow five times that.
  EXPECT_LT(Eigen::AngleAxisd(result.alignment.rotation * motion.rotation.transpose()).angle(),
            5 * 0.02 * M_PI / 180);
  EXPECT_LT((result.alignment.translation - motion.translation).norm(), 5 * 0.0007 * 3);
  // Expected RMSE: sigma * sqrt(3) = 1.73 cm (6 of 600 degrees of freedom go to the alignment);
  // the sample RMSE of 200 draws lies within 10 % of it with overwhelming probability.
  EXPECT_NEAR(result.ate.rmse, sigma * std::sqrt(3.0), 0.1 * sigma * std::sqrt(3.0));
}

TEST(Ate, HandComputedExample) {
  Trajectory reference, estimate;
  const double offsets[4][3] = {{1, 0, 0}, {0, 2, 0}, {0, 0, 0}, {0, 0, -2}};
  for (int i = 0; i < 4; ++i) {
    const Eigen::Vector3d p(i, 2.0 * i, 0.0);
    reference.push_back({static_cast<double>(i), MakePose(0, 0, 0, p)});
    estimate.push_back(
        {static_cast<double>(i),
         MakePose(0, 0, 0, p + Eigen::Vector3d(offsets[i][0], offsets[i][1], offsets[i][2]))});
  }
  EvaluationOptions options;
  options.alignment = AlignmentMode::kNone;
  const EvaluationResult result = EvaluateTrajectory(reference, estimate, options);
  // Errors 1, 2, 0, 2: RMSE sqrt(9/4) = 1.5, mean 1.25, median (1+2)/2 = 1.5, max 2.
  EXPECT_DOUBLE_EQ(result.ate.rmse, 1.5);
  EXPECT_DOUBLE_EQ(result.ate.mean, 1.25);
  EXPECT_DOUBLE_EQ(result.ate.median, 1.5);
  EXPECT_DOUBLE_EQ(result.ate.max, 2.0);
  EXPECT_EQ(result.ate.count, 4u);
}

TEST(Ate, ConstantOffsetVanishesWithAlignment) {
  Trajectory reference = Helix(), estimate = Helix();
  for (StampedPose& p : estimate) p.pose.translation() += Eigen::Vector3d(0.3, 0.0, -0.4);
  EvaluationOptions options;
  options.alignment = AlignmentMode::kNone;
  EXPECT_NEAR(EvaluateTrajectory(reference, estimate, options).ate.rmse, 0.5, 1e-12);
  options.alignment = AlignmentMode::kSE3;
  EXPECT_LT(EvaluateTrajectory(reference, estimate, options).ate.rmse, 1e-9);
}

TEST(Association, DropsPosesBeyondTheLimit) {
  Trajectory reference;
  for (int i = 0; i < 100; ++i) reference.push_back({0.1 * i, Eigen::Isometry3d::Identity()});
  Trajectory estimate = {{0.005, {}}, {0.3 + 0.0099, {}}, {0.52, {}}, {0.7 - 0.011, {}},
                         {5.0, {}},   {9.9 + 0.012, {}},  {-0.5, {}}};
  const std::vector<AssociatedPair> pairs = AssociateByTimestamp(reference, estimate, 0.01);
  ASSERT_EQ(pairs.size(), 3u);  // 0.005 -> 0.0, 0.3099 -> 0.3, 5.0 -> 5.0
  EXPECT_EQ(pairs[0].reference, 0u);
  EXPECT_EQ(pairs[0].estimate, 0u);
  EXPECT_EQ(pairs[1].reference, 3u);
  EXPECT_EQ(pairs[2].reference, 50u);
  EXPECT_EQ(pairs[2].estimate, 4u);
  // A looser limit takes 0.689 (11 ms off), then 9.912 (12 ms) and 0.52 (20 ms); -0.5 never.
  EXPECT_EQ(AssociateByTimestamp(reference, estimate, 0.0115).size(), 4u);
  EXPECT_EQ(AssociateByTimestamp(reference, estimate, 0.03).size(), 6u);
}

// As numpy's argmin in evo: of two poses equally near in time, the first in the file, whichever
// is earlier in time; and the shorter trajectory searches the longer.
TEST(Association, TiesGoToTheFirstInTheFileAndTheShorterSideSearches) {
  const Trajectory reference = {{1.25, {}}, {0.75, {}}, {3.0, {}}, {4.0, {}}};
  const Trajectory estimate = {{1.0, {}}, {3.0, {}}};
  std::vector<AssociatedPair> pairs = AssociateByTimestamp(reference, estimate, 0.25);
  ASSERT_EQ(pairs.size(), 2u);
  EXPECT_EQ(pairs[0].reference, 0u);  // 1.25 before 0.75 in the file
  EXPECT_EQ(pairs[1].reference, 2u);
  // Swapped, the estimate is the longer: the 2 reference poses search it, and 0.75, though
  // within the limit of 1.0, is left out (the estimate searching would have paired it too).
  pairs = AssociateByTimestamp(estimate, reference, 0.25);
  ASSERT_EQ(pairs.size(), 2u);
  EXPECT_EQ(pairs[0].reference, 0u);
  EXPECT_EQ(pairs[0].estimate, 0u);
  EXPECT_EQ(pairs[1].reference, 1u);
  EXPECT_EQ(pairs[1].estimate, 2u);
}

TEST(Rpe, KnownDriftPerStep) {
  // Reference: 1 m forward a frame. Estimate: 1.1 m forward and 1 degree more yaw a frame.
  Trajectory reference, estimate;
  Eigen::Isometry3d estimated = Eigen::Isometry3d::Identity();
  const Eigen::Isometry3d step = MakePose(M_PI / 180.0, 0, 0, {1.1, 0, 0});
  for (int i = 0; i < 20; ++i) {
    reference.push_back({double(i), MakePose(0, 0, 0, {double(i), 0, 0})});
    estimate.push_back({double(i), estimated});
    estimated = estimated * step;
  }
  const RelativePoseError one_frame =
      ComputeRelativePoseError(reference, estimate, {1.0, RpeDelta::Unit::kFrames});
  EXPECT_EQ(one_frame.translation.count, 19u);
  EXPECT_NEAR(one_frame.translation.rmse, 0.1, 1e-12);
  EXPECT_NEAR(one_frame.rotation_deg.rmse, 1.0, 1e-9);
  // 2 m along the reference is 2 frames: E = (2 m)^-1 * (step * step).
  const RelativePoseError two_metres =
      ComputeRelativePoseError(reference, estimate, {2.0, RpeDelta::Unit::kMeters});
  const Eigen::Isometry3d error = MakePose(0, 0, 0, {2, 0, 0}).inverse() * step * step;
  EXPECT_EQ(two_metres.translation.count, 18u);
  EXPECT_NEAR(two_metres.translation.max, error.translation().norm(), 1e-12);
  EXPECT_NEAR(two_metres.rotation_deg.mean, 2.0, 1e-9);
}

TEST(TrajectoryFiles, RoundTripInEveryFormat) {
  TemporaryDirectory temp;
  Trajectory trajectory = Helix();
  for (StampedPose& p : trajectory) p.timestamp = 1403636584.0 + p.timestamp;  // EuRoC-sized stamps
  struct Case {
    std::string file;
    TrajectoryFormat format;
  };
  for (const Case& c :
       {Case{"a.txt", TrajectoryFormat::kTum}, Case{"b.csv", TrajectoryFormat::kEuroc},
        Case{"c.kitti", TrajectoryFormat::kKitti}}) {
    const std::string path = temp.path() + "/" + c.file;
    if (c.format == TrajectoryFormat::kTum) WriteTumTrajectory(trajectory, path);
    if (c.format == TrajectoryFormat::kEuroc) WriteEurocTrajectory(trajectory, path);
    if (c.format == TrajectoryFormat::kKitti) WriteKittiTrajectory(trajectory, path);
    EXPECT_EQ(DetectTrajectoryFormat(path), c.format) << path;
    const Trajectory read = ReadTrajectory(path);
    ASSERT_EQ(read.size(), trajectory.size());
    for (std::size_t i = 0; i < read.size(); ++i) {
      // Files hold 9 decimals (TUM, EuRoC) or 10 significant digits (KITTI).
      EXPECT_LT((read[i].pose.matrix() - trajectory[i].pose.matrix()).cwiseAbs().maxCoeff(), 1e-8);
      if (c.format == TrajectoryFormat::kKitti) {
        EXPECT_EQ(read[i].timestamp, static_cast<double>(i));
      } else {
        EXPECT_NEAR(read[i].timestamp, trajectory[i].timestamp, 1e-6);
      }
    }
  }
}

TEST(TrajectoryFiles, MalformedLinesNameFileAndLine) {
  TemporaryDirectory temp;
  const std::string path = temp.path() + "/bad.txt";
  WriteTextFile(path, "# t x y z qx qy qz qw\n0 0 0 0 0 0 0 1\n1 0 0 0 0 0 1\n");
  try {
    ReadTumTrajectory(path);
    ADD_FAILURE() << "no error";
  } catch (const io::InputError& error) {
    EXPECT_NE(std::string(error.what()).find(path + ":3:"), std::string::npos) << error.what();
  }
  EXPECT_THROW(ReadTrajectory(temp.path() + "/missing.txt"), io::InputError);
}

TEST(TrajectoryFrames, BodyToCamera) {
  const Eigen::Isometry3d T_body_camera = MakePose(0.1, 0.2, -1.5, {0.02, -0.06, 0.01});
  const Trajectory body = Helix();
  const Trajectory camera = TransformToSensorFrame(body, T_body_camera);
  ASSERT_EQ(camera.size(), body.size());
  for (std::size_t i = 0; i < body.size(); ++i) {
    EXPECT_TRUE(camera[i].pose.isApprox(body[i].pose * T_body_camera, 1e-12));
    EXPECT_EQ(camera[i].timestamp, body[i].timestamp);
  }
}

TEST(ErrorStatistics, EmptyAndOddCounts) {
  EXPECT_EQ(Summarize({}).count, 0u);
  const ErrorStatistics odd = Summarize({3.0, 1.0, 2.0});
  EXPECT_DOUBLE_EQ(odd.median, 2.0);
  EXPECT_DOUBLE_EQ(odd.rmse, std::sqrt(14.0 / 3.0));
}

}  // namespace
}  // namespace stereo_fabmap_slam::test
