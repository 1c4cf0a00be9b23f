// Relocalization on a rendered route (make_synthetic_sequence's hall, exact ground truth, the
// default vocabulary): frames of the second lap are found in a map of the first lap, with the
// pose error the issue asks for; frames of a part of the hall the map never saw are refused,
// although the hall repeats its photos on purpose.
#include <algorithm>
#include <cmath>
#include <limits>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "slam_configuration.h"
#include "stereo_fabmap_slam/datasets/euroc_sequence.h"
#include "stereo_fabmap_slam/datasets/route.h"
#include "stereo_fabmap_slam/evaluation/trajectory_metrics.h"
#include "stereo_fabmap_slam/pipeline/stereo_slam.h"
#include "test_support.h"

namespace stereo_fabmap_slam::test {
namespace {

constexpr char kConfig[] = STEREO_FABMAP_SLAM_REPO_ROOT "/config/euroc.yaml";
constexpr char kFabmapConfig[] = STEREO_FABMAP_SLAM_REPO_ROOT "/config/fabmap.yaml";

double Median(std::vector<double> values) {
  std::nth_element(values.begin(), values.begin() + values.size() / 2, values.end());
  return values[values.size() / 2];
}

class RenderedRoute : public ::testing::Test {
 protected:
  // The loop the loop-closing tests and rostests map (rendered once for all of them): a lap and
  // about seven seconds of the second.
  static void SetUpTestSuite() {
    directory_ = SharedSyntheticSequence(MAKE_SYNTHETIC_SEQUENCE_BIN, "loop", 34, 1);
    lap_time_ = datasets::Route(datasets::RouteKind::kLoop, datasets::HallOptions()).lap_time();
  }

  // A SLAM with loop closing and relocalization, fed the frames with timestamps in [0, until).
  struct Slam {
    datasets::EurocSequence sequence;
    camera::StereoRectifier rectifier;
    pipeline::StereoSlam slam;
    evaluation::Trajectory truth;  // rectified left camera

    // The pose of the rectified left camera at `time` (exact: frames lie on ground-truth stamps).
    Eigen::Isometry3d Truth(double time) const {
      double best = std::numeric_limits<double>::max();
      Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
      for (const auto& entry : truth) {
        if (std::abs(entry.timestamp - time) < best) {
          best = std::abs(entry.timestamp - time);
          pose = entry.pose;
        }
      }
      EXPECT_LT(best, 1e-3);
      return pose;
    }
  };

  static std::unique_ptr<Slam> MapUntil(double until) {
    tools::SlamConfiguration options = tools::SlamConfiguration::Load(kConfig);
    const place_recognition::PlaceRecognitionOptions place_options =
        place_recognition::LoadPlaceRecognitionOptions(kFabmapConfig, options.front_end.features);
    options.front_end.place_features = place_options.features;
    datasets::EurocSequence sequence = datasets::EurocSequence::Open(directory_);
    camera::StereoRectifier rectifier =
        camera::StereoRectifier::FromCalibration(sequence.calibration(), options.rectification);
    auto slam = std::unique_ptr<Slam>(
        new Slam{sequence, rectifier,
                 pipeline::StereoSlam(options.front_end, options.bundle_adjustment, rectifier,
                                      [] { return 0.0; }),
                 evaluation::TransformToSensorFrame(sequence.ground_truth(),
                                                    rectifier.T_body_rectified_left())});
    slam->slam.EnableLoopClosing(pipeline::PlaceStage::LoadDetector(
                                     place_options, options.loop_detection, rectifier.camera(),
                                     slam->slam.descriptor_norm(), slam->slam.max_match_distance()),
                                 options.pose_graph, options.relocalization);
    const double start = sequence.frames().front().timestamp_ns * 1e-9;
    for (std::size_t i = 0; i < sequence.size(); ++i) {
      const datasets::StereoImages images = sequence.LoadStereoPair(i);
      if (images.timestamp_ns * 1e-9 - start >= until) break;
      slam->slam.ProcessFrame(images.timestamp_ns * 1e-9, images.left, images.right);
    }
    return slam;
  }

  static std::string directory_;
  static double lap_time_;
};

std::string RenderedRoute::directory_;
double RenderedRoute::lap_time_ = 0;

TEST_F(RenderedRoute, SecondLapIsFoundInTheFirstLapsMap) {
  std::unique_ptr<Slam> run = MapUntil(lap_time_);
  const double start = run->sequence.frames().front().timestamp_ns * 1e-9;
  std::vector<double> translation_errors, rotation_errors;
  int attempts = 0;
  // Every 4th frame of the second lap (the route continues past the start for a while).
  for (std::size_t i = 0; i < run->sequence.size(); i += 4) {
    const double time = run->sequence.frames()[i].timestamp_ns * 1e-9;
    if (time - start < lap_time_) continue;
    const datasets::StereoImages images = run->sequence.LoadStereoPair(i);
    const pipeline::RelocalizationOutput found = run->slam.Relocalize(images.left, images.right);
    ++attempts;
    if (!found.result.success()) continue;
    // The relocalization's own error: the frame relative to the keyframe it was found against,
    // against the same relative pose in ground truth (the map's drift is not the relocalizer's).
    const Eigen::Isometry3d truth =
        run->Truth(run->slam.KeyframeTime(found.result.keyframe_id)).inverse() * run->Truth(time);
    const Eigen::Isometry3d error = truth.inverse() * found.result.T_keyframe_camera;
    translation_errors.push_back(error.translation().norm());
    rotation_errors.push_back(Eigen::AngleAxisd(error.linear()).angle() * 180.0 / M_PI);
    EXPECT_LT(translation_errors.back(), 0.5) << "a wrong relocalization at " << time - start;
  }
  ASSERT_GT(attempts, 10);
  const double found_share = static_cast<double>(translation_errors.size()) / attempts;
  RecordProperty("found",
                 std::to_string(translation_errors.size()) + "/" + std::to_string(attempts));
  // The second lap retraces the first: nearly all of its views are found.
  // Measured: 35 of 35 here (and 45 of 45 on a 36 s loop of seed 4); 0.9 leaves room for three
  // views of 35 that a hall with other photos may not find.
  EXPECT_GT(found_share, 0.9);
  ASSERT_FALSE(translation_errors.empty());
  RecordProperty("median_translation_error_m", std::to_string(Median(translation_errors)));
  RecordProperty("median_rotation_error_deg", std::to_string(Median(rotation_errors)));
  EXPECT_LT(Median(translation_errors), 0.02);
  EXPECT_LT(Median(rotation_errors), 1.0);
}

TEST_F(RenderedRoute, PlacesNeverMappedAreRefused) {
  // A map of the first fifth of the lap; queries from the second half of the lap, on the far
  // side of the hall, where the same photos hang on other walls.
  std::unique_ptr<Slam> run = MapUntil(0.2 * lap_time_);
  const double start = run->sequence.frames().front().timestamp_ns * 1e-9;
  int attempts = 0, wrong = 0, found = 0;
  for (std::size_t i = 0; i < run->sequence.size(); i += 4) {
    const double time = run->sequence.frames()[i].timestamp_ns * 1e-9 - start;
    if (time < 0.45 * lap_time_ || time > 0.8 * lap_time_) continue;
    const datasets::StereoImages images = run->sequence.LoadStereoPair(i);
    const pipeline::RelocalizationOutput result = run->slam.Relocalize(images.left, images.right);
    ++attempts;
    if (!result.result.success()) continue;
    ++found;
    const Eigen::Isometry3d truth =
        run->Truth(run->slam.KeyframeTime(result.result.keyframe_id)).inverse() *
        run->Truth(time + start);
    wrong += (truth.inverse() * result.result.T_keyframe_camera).translation().norm() > 0.5;
  }
  ASSERT_GT(attempts, 10);
  EXPECT_EQ(found, 0) << wrong << " of them wrong";
}

}  // namespace
}  // namespace stereo_fabmap_slam::test
