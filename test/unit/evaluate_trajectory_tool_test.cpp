// The evaluate_trajectory program, run as a user runs it.
#include <regex>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>

#include "stereo_fabmap_slam/camera/camera_calibration.h"
#include "stereo_fabmap_slam/datasets/euroc_sequence.h"
#include "stereo_fabmap_slam/evaluation/trajectory_metrics.h"
#include "stereo_fabmap_slam/io/trajectory_file.h"
#include "test_support.h"

namespace stereo_fabmap_slam::test {
namespace {

double JsonNumber(const std::string& json, const std::string& key) {
  const std::regex pattern("\"" + key + "\": ([-0-9.eE+]+)");
  std::smatch match;
  if (!std::regex_search(json, match, pattern)) {
    ADD_FAILURE() << key << " not in " << json;
    return -1;
  }
  return std::stod(match[1]);
}

class EvaluateTrajectoryTool : public ::testing::Test {
 protected:
  void SetUp() override {
    const std::string mav0 = EurocSequencePath("MH01_first10s") + "/mav0";
    gt_path_ = mav0 + "/state_groundtruth_estimate0/data.csv";
    sensor_yaml_ = mav0 + "/cam0/sensor.yaml";
    // An "estimate": the left camera's true path at the ground-truth stamps nearest the images,
    // 20 cm off, which SE(3) alignment removes exactly.
    const datasets::EurocSequence sequence = datasets::EurocSequence::Open(mav0);
    const evaluation::Trajectory camera_truth = evaluation::TransformToSensorFrame(
        sequence.ground_truth(), sequence.calibration().left.T_body_camera);
    std::size_t k = 0;
    for (const datasets::StereoFrameEntry& frame : sequence.frames()) {
      const double t = frame.timestamp_ns * 1e-9;
      while (k + 1 < camera_truth.size() && camera_truth[k + 1].timestamp <= t) ++k;
      evaluation::StampedPose pose = camera_truth[k];
      pose.pose.translation() += Eigen::Vector3d(0.2, 0.0, 0.0);
      estimate_.push_back(pose);
    }
    est_path_ = temp_.path() + "/estimate.txt";
    io::WriteTumTrajectory(estimate_, est_path_);
    camera_truth_ = camera_truth;
  }

  std::string Run(const std::string& arguments, int* status) {
    std::string output;
    *status = RunCommand(std::string(EVALUATE_TRAJECTORY_BIN) + " " + arguments + " 2>&1", &output);
    return output;
  }

  TemporaryDirectory temp_;
  std::string gt_path_, sensor_yaml_, est_path_;
  evaluation::Trajectory estimate_, camera_truth_;
};

TEST_F(EvaluateTrajectoryTool, JsonMatchesTheLibrary) {
  int status = -1;
  const std::string json = Run(
      "--gt " + gt_path_ + " --est " + est_path_ + " --gt-to-camera " + sensor_yaml_ + " --json",
      &status);
  ASSERT_EQ(status, 0) << json;
  const evaluation::EvaluationResult expected =
      evaluation::EvaluateTrajectory(camera_truth_, io::ReadTrajectory(est_path_), {});
  EXPECT_EQ(JsonNumber(json, "matched"), 200);
  EXPECT_NEAR(JsonNumber(json, "ate_rmse"), expected.ate.rmse, 1e-8);
  EXPECT_NEAR(JsonNumber(json, "ate_max"), expected.ate.max, 1e-8);
  EXPECT_NEAR(JsonNumber(json, "rpe_trans_rmse"), expected.rpe.translation.rmse, 1e-8);
  for (const std::string key : {"ate_mean", "ate_median", "rpe_rot_rmse_deg"})
    JsonNumber(json, key);
  // The constant offset is removed by alignment; what remains is the files' 9 decimals.
  EXPECT_LT(JsonNumber(json, "ate_rmse"), 1e-7);
}

TEST_F(EvaluateTrajectoryTool, GroundTruthInTheWrongFrameIsWorse) {
  int status = -1;
  const std::string json = Run("--gt " + gt_path_ + " --est " + est_path_ + " --json", &status);
  ASSERT_EQ(status, 0) << json;
  // Body and camera are ~7 cm apart and the camera rotates: comparing positions of different
  // frames leaves an error no rigid alignment removes (here several millimetres).
  EXPECT_GT(JsonNumber(json, "ate_rmse"), 0.002);
}

// Pixels of (nearly) one BGR colour in a region of the image.
int CountColour(const cv::Mat& image, const cv::Rect& region, const cv::Scalar& colour) {
  cv::Mat mask;
  cv::inRange(image(region), colour - cv::Scalar(30, 30, 30), colour + cv::Scalar(30, 30, 30),
              mask);
  return cv::countNonZero(mask);
}

TEST_F(EvaluateTrajectoryTool, TableAndPlotWithLoopsAndRelocalizations) {
  int status = -1;
  const std::string plot = temp_.path() + "/plot.png";
  // A loop edge and a relocalization between frames 3 s apart (the subset moves ~0.4 m).
  const double t0 = estimate_[20].timestamp, t1 = estimate_[80].timestamp;
  const double t2 = estimate_[100].timestamp, t3 = estimate_[160].timestamp;
  WriteTextFile(temp_.path() + "/loops.txt",
                "# query match\n" + std::to_string(t1) + " " + std::to_string(t0) + "\n");
  WriteTextFile(temp_.path() + "/relocalizations.txt",
                std::to_string(t3) + " " + std::to_string(t2) + "\n");
  const std::string table =
      Run("--gt " + gt_path_ + " --est " + est_path_ + " --gt-to-camera " + sensor_yaml_ +
              " --align sim3 --plot " + plot + " --loops " + temp_.path() + "/loops.txt" +
              " --relocalizations " + temp_.path() + "/relocalizations.txt",
          &status);
  ASSERT_EQ(status, 0) << table;
  EXPECT_NE(table.find("ATE [cm]"), std::string::npos) << table;
  EXPECT_NE(table.find("sim3"), std::string::npos) << table;
  const cv::Mat image = cv::imread(plot);
  ASSERT_FALSE(image.empty());
  // Top view on the left, side view on the right, each with the estimate (blue-orange), the
  // loop edge (red) and the relocalization (magenta).
  ASSERT_EQ(image.size(), cv::Size(1600, 650));
  for (const cv::Rect half : {cv::Rect(0, 0, 800, 650), cv::Rect(800, 0, 800, 650)}) {
    EXPECT_GT(CountColour(image, half, cv::Scalar(200, 90, 0)), 50) << half;
    EXPECT_GT(CountColour(image, half, cv::Scalar(40, 40, 230)), 20) << half;
    EXPECT_GT(CountColour(image, half, cv::Scalar(200, 40, 200)), 20) << half;
  }
}

// Base poses (ROS's base_link, T_body_base of config/euroc_stereo.yaml: rotated from the body)
// match the ground truth moved to the base, not the body's: the relative motions differ by the
// rotation, which no alignment of the whole trajectory removes.
TEST_F(EvaluateTrajectoryTool, GroundTruthMovedToTheBase) {
  const std::string calibration = RepositoryRoot() + "/config/euroc_stereo.yaml";
  const Eigen::Isometry3d T_body_base = camera::ReadStereoCalibrationYaml(calibration).T_body_base;
  const evaluation::Trajectory base = evaluation::TransformToSensorFrame(
      datasets::EurocSequence::Open(EurocSequencePath("MH01_first10s")).ground_truth(),
      T_body_base);
  const std::string base_path = temp_.path() + "/base.txt";
  io::WriteTumTrajectory(base, base_path);
  int status = -1;
  const std::string matched =
      Run("--gt " + gt_path_ + " --est " + base_path + " --gt-to-base " + calibration + " --json",
          &status);
  ASSERT_EQ(status, 0) << matched;
  EXPECT_LT(JsonNumber(matched, "ate_rmse"), 1e-6);
  EXPECT_LT(JsonNumber(matched, "rpe_trans_rmse"), 1e-6);
  const std::string body = Run("--gt " + gt_path_ + " --est " + base_path + " --json", &status);
  ASSERT_EQ(status, 0) << body;
  EXPECT_GT(JsonNumber(body, "rpe_trans_rmse"), 1e-4);
  const std::string both = Run("--gt " + gt_path_ + " --est " + base_path + " --gt-to-base " +
                                   calibration + " --gt-to-camera " + sensor_yaml_,
                               &status);
  EXPECT_EQ(status, 2);
  EXPECT_NE(both.find("at most one of"), std::string::npos) << both;
}

// A file repeating every stamp (as a visual-inertial system's output may): evaluated, not
// refused, with a warning; the repeated poses are equal here, so the ATE stays that of the
// estimate alone.
TEST_F(EvaluateTrajectoryTool, RepeatedStampsAreEvaluatedWithAWarning) {
  evaluation::Trajectory doubled;
  for (const auto& pose : estimate_) {
    doubled.push_back(pose);
    doubled.push_back(pose);
  }
  const std::string path = temp_.path() + "/doubled.txt";
  io::WriteTumTrajectory(doubled, path);
  int status = -1;
  const std::string output =
      Run("--gt " + gt_path_ + " --est " + path + " --gt-to-camera " + sensor_yaml_ + " --json",
          &status);
  ASSERT_EQ(status, 0) << output;
  EXPECT_NE(output.find("200 repeated and 0 decreasing timestamps"), std::string::npos) << output;
  EXPECT_EQ(JsonNumber(output, "matched"), 400);
  EXPECT_LT(JsonNumber(output, "ate_rmse"), 1e-7);
}

TEST_F(EvaluateTrajectoryTool, ExtraPosesAreMeasuredWithTheEstimatesAlignment) {
  // Two poses in the estimate's frame (20 cm off like it): one true, one 10 cm further off.
  evaluation::Trajectory poses = {estimate_[50], estimate_[120]};
  poses[1].pose.translation() += Eigen::Vector3d(0.0, 0.1, 0.0);
  const std::string path = temp_.path() + "/poses.txt";
  io::WriteTumTrajectory(poses, path);
  int status = -1;
  const std::string table = Run("--gt " + gt_path_ + " --est " + est_path_ + " --gt-to-camera " +
                                    sensor_yaml_ + " --poses " + path,
                                &status);
  ASSERT_EQ(status, 0) << table;
  const std::regex line("pose [0-9.]+: ([0-9.]+) m, ([0-9.]+) deg");
  std::vector<double> errors;
  for (std::sregex_iterator it(table.begin(), table.end(), line), end; it != end; ++it) {
    errors.push_back(std::stod((*it)[1]));
  }
  ASSERT_EQ(errors.size(), 2u) << table;
  // The estimate is the truth shifted rigidly, so the alignment is exact to the stamps' offset
  // (ground truth at 200 Hz, nearest sample): a few millimetres at most.
  EXPECT_LT(errors[0], 0.005);
  EXPECT_NEAR(errors[1], 0.1, 0.005);
  const std::string refused =
      Run("--gt " + gt_path_ + " --est " + est_path_ + " --poses " + path + " --json", &status);
  EXPECT_EQ(status, 2);
  EXPECT_NE(refused.find("--poses prints a table"), std::string::npos) << refused;
}

TEST_F(EvaluateTrajectoryTool, BadArgumentsAndFiles) {
  int status = -1;
  Run("--gt " + gt_path_, &status);
  EXPECT_EQ(status, 2);
  Run("--gt " + gt_path_ + " --est " + est_path_ + " --align affine", &status);
  EXPECT_EQ(status, 2);
  const std::string message =
      Run("--gt " + gt_path_ + " --est " + temp_.path() + "/none.txt", &status);
  EXPECT_EQ(status, 1);
  EXPECT_NE(message.find("none.txt: cannot open file"), std::string::npos) << message;
  // Stamps that never meet: a clear message, not a crash.
  evaluation::Trajectory shifted = estimate_;
  for (auto& p : shifted) p.timestamp += 1000.0;
  io::WriteTumTrajectory(shifted, est_path_);
  const std::string no_match = Run("--gt " + gt_path_ + " --est " + est_path_, &status);
  EXPECT_EQ(status, 1);
  EXPECT_NE(no_match.find("have a reference pose within"), std::string::npos) << no_match;
}

}  // namespace
}  // namespace stereo_fabmap_slam::test
