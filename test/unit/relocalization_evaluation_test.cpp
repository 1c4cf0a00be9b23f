// The thesis' relocalization measure: relevance of a keyframe to a view on hand-built geometry,
// recall and summary on hand-made trials, and evaluate_relocalization as a user runs it on a
// short rendered route.
#include <cmath>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "stereo_fabmap_slam/evaluation/relocalization_recall.h"
#include "test_support.h"

namespace stereo_fabmap_slam::test {
namespace {

geometry::StereoCamera Camera() {
  geometry::StereoCamera camera;
  camera.size = cv::Size(640, 480);
  camera.fx = camera.fy = 400;
  camera.cx = 319.5;
  camera.cy = 239.5;
  camera.baseline = 0.1;
  return camera;
}

// A 10 x 10 grid of points 4 m in front of the keyframe, columns at x = -1.9 ... 1.7 m. At 4 m
// depth with fx = 400 a metre is 100 px, so all of it lies inside the 640 x 480 image; seen from
// 3.2 m to the keyframe's left, the columns land at u = 449.5 ... 809.5 px: five inside, five
// beyond the right border.
std::vector<Eigen::Vector3d> GridInFront() {
  std::vector<Eigen::Vector3d> points;
  for (int row = 0; row < 10; ++row) {
    for (int column = 0; column < 10; ++column) {
      points.emplace_back(-1.9 + 0.4 * column, -1.0 + 0.2 * row, 4.0);
    }
  }
  return points;
}

TEST(RelocalizationEvaluation, KeyframeHalfInsideTheViewIsHalfVisible) {
  const std::vector<Eigen::Vector3d> points = GridInFront();
  Eigen::Isometry3d T_view_keyframe = Eigen::Isometry3d::Identity();
  EXPECT_DOUBLE_EQ(evaluation::VisibleFraction(points, T_view_keyframe, Camera()), 1.0);
  // The view 3.2 m to the keyframe's left: the keyframe's points move 3.2 m right in it.
  T_view_keyframe.translation() = Eigen::Vector3d(3.2, 0, 0);
  EXPECT_DOUBLE_EQ(evaluation::VisibleFraction(points, T_view_keyframe, Camera()), 0.5);
  // Turned around, the view sees none of them, although they project inside its image.
  T_view_keyframe = Eigen::Isometry3d::Identity();
  T_view_keyframe.linear() = Eigen::AngleAxisd(M_PI, Eigen::Vector3d::UnitY()).toRotationMatrix();
  EXPECT_DOUBLE_EQ(evaluation::VisibleFraction(points, T_view_keyframe, Camera()), 0.0);
  EXPECT_DOUBLE_EQ(evaluation::VisibleFraction({}, Eigen::Isometry3d::Identity(), Camera()), 0.0);
}

evaluation::RelocalizationTrial Trial(double relevance, bool estimated, double error_m) {
  evaluation::RelocalizationTrial trial;
  trial.relevance = relevance;
  trial.estimated = estimated;
  trial.error_m = error_m;
  return trial;
}

TEST(RelocalizationEvaluation, RecallCountsRelevantFramesFoundWithinTheError) {
  // Relevant at tau 0.9: the first four. Found within 0.5 m: the first two; within 0.1 m: one.
  const std::vector<evaluation::RelocalizationTrial> trials = {
      Trial(1.0, true, 0.05), Trial(0.95, true, 0.3), Trial(0.92, true, 0.8),
      Trial(0.9, false, 0),   Trial(0.5, true, 0.01), Trial(0.0, false, 0)};
  EXPECT_DOUBLE_EQ(evaluation::RelocalizationRecall(trials, 0.9, 0.5), 2.0 / 4.0);
  EXPECT_DOUBLE_EQ(evaluation::RelocalizationRecall(trials, 0.9, 0.1), 1.0 / 4.0);
  EXPECT_DOUBLE_EQ(evaluation::RelocalizationRecall(trials, 0.9, 1.0), 3.0 / 4.0);
  EXPECT_DOUBLE_EQ(evaluation::RelocalizationRecall(trials, 0.0, 0.5), 3.0 / 6.0);
  EXPECT_DOUBLE_EQ(evaluation::RelocalizationRecall(trials, 1.01, 0.5), 0.0);  // none relevant

  const evaluation::RelocalizationSummary summary =
      evaluation::SummarizeRelocalization(trials, 0.9, 0.5);
  EXPECT_EQ(summary.test_frames, 6);
  EXPECT_EQ(summary.relevant_frames, 4);
  EXPECT_EQ(summary.estimated_frames, 4);
  EXPECT_EQ(summary.wrong_estimates, 1);                     // the 0.8 m one
  EXPECT_DOUBLE_EQ(summary.error_below_10cm_fraction, 0.5);  // 0.05 and 0.01 of four
  EXPECT_DOUBLE_EQ(summary.error_median_m, 0.5 * (0.05 + 0.3));
  EXPECT_TRUE(std::isnan(
      evaluation::SummarizeRelocalization({Trial(1.0, false, 0)}, 0.9, 0.5).error_median_m));
}

TEST(RelocalizationEvaluation, ToolOnRenderedRouteRelocalizesMostRelevantFrames) {
  TemporaryDirectory temp;
  std::string output;
  // 16 s of the rendered loop: the map of the first 10 s, every second frame of the last 6 s
  // relocalized against it (the camera moves on away from the map, so relevance falls).
  ASSERT_EQ(RunCommand(std::string(MAKE_SYNTHETIC_SEQUENCE_BIN) + " --output " + temp.path() +
                           "/sequence --route loop --seconds 16 --seed 3 --no-bag 2>&1",
                       &output),
            0)
      << output;
  ASSERT_EQ(RunCommand(std::string(EVALUATE_RELOCALIZATION_BIN) + " " + temp.path() +
                           "/sequence --map-until 10 --every 2 --json --quiet --output " +
                           temp.path() + "/evaluation",
                       &output),
            0)
      << output;
  RecordProperty("summary", output);
  for (const char* key : {"test_frames", "relevant_frames", "estimated_frames", "recall",
                          "error_below_10cm_fraction", "error_median_m", "wrong_estimates"}) {
    EXPECT_NE(output.find(std::string("\"") + key + "\":"), std::string::npos) << key;
  }
  EXPECT_EQ(JsonNumber(output, "test_frames"), 60);  // 120 frames after 10 s, one in two
  EXPECT_GT(JsonNumber(output, "relevant_frames"), 0);
  // The target on a rendered route; measured 1.0 on 34 s of the loop mapped to 26 s.
  EXPECT_GE(JsonNumber(output, "recall"), 0.8);
  EXPECT_EQ(ReadTextFile(temp.path() + "/evaluation/frames.csv").rfind("time,mapping,x,y,z,", 0),
            0u);
  EXPECT_EQ(ReadTextFile(temp.path() + "/evaluation/summary.json"), output);
}

}  // namespace
}  // namespace stereo_fabmap_slam::test
