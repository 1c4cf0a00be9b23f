// The tracking stage's watch on its input and its relocalization policy, without ROS: every
// input fault the StereoTracker nodelet meets (a wrong size, a frozen camera, a gap, time going
// backwards, blank images, a camera that drops out, images that do not pair up, pairs the tracker
// had no time for) is counted and named here, on real V101 frames; and when the stage asks the
// place stage to find the camera, and what it makes of the answer.
#include "stereo_fabmap_slam/pipeline/tracking_stage.h"

#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <opencv2/imgproc.hpp>

#include "stereo_fabmap_slam/datasets/euroc_sequence.h"
#include "test_support.h"

namespace stereo_fabmap_slam::test {
namespace {

using pipeline::InputEvent;
using pipeline::RelocalizationRequest;

bool HasEvent(const std::vector<InputEvent>& events, InputEvent::Kind kind,
              const std::string& text) {
  for (const InputEvent& event : events) {
    if (event.kind == kind && event.message.find(text) != std::string::npos) return true;
  }
  return false;
}

// A map with one keyframe, as a map_graph would say: what makes a loss a reason to recover.
pipeline::MapSnapshot MapWithAKeyframe() {
  pipeline::MapSnapshot map;
  map.keyframes[0] = {Eigen::Isometry3d::Identity(), true};
  return map;
}

class TrackingStageTest : public ::testing::Test {
 protected:
  TrackingStageTest()
      : sequence_(datasets::EurocSequence::Open(EurocSequencePath("V101_micro"))),
        rectifier_(camera::StereoRectifier::FromCalibration(sequence_.calibration())) {
    pipeline::FrontEndOptions options;
    options.tracker.parallel = false;
    options.place_features = options.features;  // so that relocalization can be asked
    // The first success joins a new segment (confirmation by a second view has its own test,
    // relocalization_policy_test's): the stage's answers, not the policy's, are tested here.
    relocalization::RelocalizerOptions relocalization;
    relocalization.confirm_distance = 0;
    stage_ = std::make_unique<pipeline::TrackingStage>(
        options, rectifier_, pipeline::InputMonitorOptions(), relocalization, [] { return 0.0; });
    stamp_ = sequence_.frames()[0].timestamp_ns * 1e-9;
  }

  // The next pair of the hovering camera (any frame of it follows any other) at the next stamp.
  pipeline::TrackingOutput Next(const cv::Mat* left = nullptr, const cv::Mat* right = nullptr,
                                double step = kStep) {
    const datasets::StereoImages images =
        sequence_.LoadStereoPair(next_frame_++ % sequence_.frames().size());
    stamp_ += step;
    return stage_->Process(
        {stamp_, left ? *left : images.left, right ? *right : images.right, ++arrival_}, &map_);
  }

  static constexpr double kStep = 0.05;  // 20 Hz
  datasets::EurocSequence sequence_;
  camera::StereoRectifier rectifier_;
  std::unique_ptr<pipeline::TrackingStage> stage_;
  pipeline::MapSnapshot map_;  // empty: no recovery asked
  double stamp_ = 0;
  std::size_t next_frame_ = 0;
  std::uint64_t arrival_ = 0;
};

TEST_F(TrackingStageTest, RealFramesAreTrackedAndCounted) {
  for (int i = 0; i < 5; ++i) {
    const pipeline::TrackingOutput output = Next();
    ASSERT_TRUE(output.tracked);
    EXPECT_NE(output.tracking.state, odometry::TrackingState::kLost) << output.tracking.reason;
    EXPECT_TRUE(output.events.empty());
  }
  EXPECT_EQ(stage_->input().counts().tracked, 5u);
  EXPECT_EQ(stage_->input().counts().refused, 0u);
}

TEST_F(TrackingStageTest, AnotherSizeThanTheCalibrationsIsRefusedAndNamed) {
  ASSERT_TRUE(Next().tracked);
  const datasets::StereoImages pair = sequence_.LoadStereoPair(3);
  cv::Mat left, right;
  cv::resize(pair.left, left, cv::Size(376, 240));
  cv::resize(pair.right, right, cv::Size(376, 240));
  const pipeline::TrackingOutput refused = Next(&left, &right);
  EXPECT_FALSE(refused.tracked);
  EXPECT_TRUE(HasEvent(refused.events, InputEvent::Kind::kWrongSize,
                       "image size 376x240 / 376x240 differs from the calibration's 752x480"));
  EXPECT_EQ(stage_->input().counts().refused, 1u);
  EXPECT_TRUE(Next().tracked) << "tracking goes on after the refused pair";
}

TEST_F(TrackingStageTest, AFrozenCamerasRepeatsAreRefusedUntilItsImageChanges) {
  const datasets::StereoImages frozen = sequence_.LoadStereoPair(2);
  EXPECT_TRUE(Next(&frozen.left, &frozen.right).tracked) << "the first of them is a frame";
  for (int repeat = 1; repeat <= 3; ++repeat) {
    const pipeline::TrackingOutput output = Next(&frozen.left, &frozen.right);
    EXPECT_FALSE(output.tracked) << "a repeated image is not a frame";
    EXPECT_TRUE(HasEvent(output.events, InputEvent::Kind::kFrozen,
                         "the left and right cameras are frozen: the same image " +
                             std::to_string(repeat) + " time(s)"));
  }
  // Only the right camera frozen: named as such.
  const datasets::StereoImages other = sequence_.LoadStereoPair(4);
  const pipeline::TrackingOutput right_only = Next(&other.left, &frozen.right);
  EXPECT_FALSE(right_only.tracked);
  EXPECT_TRUE(HasEvent(right_only.events, InputEvent::Kind::kFrozen, "the right camera is"));
  const pipeline::TrackingOutput changed = Next();
  EXPECT_TRUE(changed.tracked);
  EXPECT_TRUE(
      HasEvent(changed.events, InputEvent::Kind::kUnfrozen, "change again after 4 frozen frame"));
  EXPECT_EQ(stage_->input().counts().refused, 4u);
}

TEST_F(TrackingStageTest, AGapIsNamedAndTrackedAcross) {
  ASSERT_TRUE(Next().tracked);
  const pipeline::TrackingOutput across = Next(nullptr, nullptr, 3.0);
  EXPECT_TRUE(HasEvent(across.events, InputEvent::Kind::kGap, "no stereo pairs for 3.0 s"));
  EXPECT_NE(across.tracking.state, odometry::TrackingState::kLost) << across.tracking.reason;
  EXPECT_FALSE(across.tracking.keyframe && across.tracking.keyframe->starts_new_segment)
      << "the odometry goes on across a gap of a camera that stood still";
}

TEST_F(TrackingStageTest, TimeGoingBackwardsResetsIntoANewSegmentThatIsFoundAgain) {
  map_ = MapWithAKeyframe();
  for (int i = 0; i < 3; ++i) ASSERT_TRUE(Next().tracked);
  const pipeline::TrackingOutput reset = Next(nullptr, nullptr, -1.0);
  EXPECT_TRUE(HasEvent(reset.events, InputEvent::Kind::kTimeBackwards, "time went backwards"));
  ASSERT_TRUE(reset.tracking.keyframe.has_value());
  EXPECT_TRUE(reset.tracking.keyframe->starts_new_segment);
  // The new segment is not in the map: the stage asks for it to be found there, among the map's
  // keyframes only, with an edge to join it.
  ASSERT_TRUE(reset.relocalization.has_value());
  EXPECT_EQ(reset.relocalization->scope, RelocalizationRequest::Scope::kMap);
  EXPECT_TRUE(reset.relocalization->add_edge);
  EXPECT_EQ(reset.relocalization->reference_keyframe, reset.tracking.keyframe->id);
  EXPECT_FALSE(stage_->on_map());
  EXPECT_FALSE(stage_->RecordFrame(reset, stamp_, nullptr).on_map) << "the record says so too";
  pipeline::RelocalizationAnswer found;
  found.result.status = relocalization::RelocalizationStatus::kSuccess;
  found.result.keyframe_id = 0;
  found.result.reason = "42 inliers";
  found.map_pose_known = true;
  found.ms = 7.5;
  const pipeline::RelocalizationOutcome outcome =
      stage_->OnRelocalization(*reset.relocalization, found);
  // Said as what it was, not as a tracking loss.
  EXPECT_NE(outcome.news.find("after time went backwards"), std::string::npos) << outcome.news;
  EXPECT_TRUE(stage_->on_map());
  // Both drivers' record of the frame: its tracking, the attempt, and on the map after it.
  const pipeline::FrameRecord record = stage_->RecordFrame(reset, stamp_, &found);
  EXPECT_EQ(record.timestamp, stamp_);
  EXPECT_EQ(record.reference_keyframe, reset.tracking.reference_keyframe);
  EXPECT_TRUE(record.is_keyframe);
  EXPECT_TRUE(record.on_map);
  EXPECT_TRUE(record.relocalized);
  EXPECT_EQ(record.timing.relocalization_ms, 7.5);
  ASSERT_TRUE(record.relocalization.has_value());
  EXPECT_NE(record.relocalization->find("against keyframe 0: 42 inliers"), std::string::npos)
      << *record.relocalization;
  pipeline::RelocalizationAnswer joined = found;
  joined.already_joined = true;  // a loop had joined the segment: nothing was tried
  EXPECT_FALSE(stage_->RecordFrame(reset, stamp_, &joined).relocalization.has_value());
  EXPECT_FALSE(Next().relocalization.has_value()) << "found: nothing more to ask";
}

TEST_F(TrackingStageTest, BlankImagesLoseTrackingAndRealFramesGoOn) {
  map_ = MapWithAKeyframe();
  ASSERT_TRUE(Next().tracked);
  const cv::Mat black(480, 752, CV_8UC1, cv::Scalar(0));
  const pipeline::TrackingOutput blank = Next(&black, &black);
  EXPECT_TRUE(blank.tracked) << "a blank pair is input, not a fault of it";
  EXPECT_EQ(blank.tracking.state, odometry::TrackingState::kLost);
  EXPECT_FALSE(blank.relocalization.has_value()) << "no pose, nothing to find";
  EXPECT_FALSE(stage_->on_map());
  bool tracked = false;
  for (int i = 0; i < 4 && !tracked; ++i) {
    tracked = Next().tracking.state != odometry::TrackingState::kLost;
  }
  EXPECT_TRUE(tracked) << "tracking resumes with real frames";
}

TEST_F(TrackingStageTest, AMessageThatIsNoImageIsRefusedCountedAndNamed) {
  ASSERT_TRUE(Next().tracked);
  const pipeline::TrackingOutput refused = stage_->Refuse("unsupported image encoding (rgb8)");
  EXPECT_FALSE(refused.tracked);
  EXPECT_TRUE(HasEvent(refused.events, InputEvent::Kind::kUnreadable,
                       "unsupported image encoding (rgb8); frame skipped"));
  EXPECT_EQ(stage_->input().counts().refused, 1u);
  EXPECT_EQ(stage_->input().counts().tracked, 1u);
  EXPECT_TRUE(Next().tracked) << "tracking goes on after the refused pair";
}

TEST_F(TrackingStageTest, WithoutAMapToFollowEveryFrameIsOnTheMap) {
  // No loop closing (no map given): the odometry is the map, lost frames included, as
  // run_dataset --no-loop-closing and a graph with loop_closing false both record it.
  const datasets::StereoImages images = sequence_.LoadStereoPair(0);
  const cv::Mat black(480, 752, CV_8UC1, cv::Scalar(0));
  const pipeline::TrackingOutput first =
      stage_->Process({stamp_ + kStep, images.left, images.right, 1}, nullptr);
  const pipeline::TrackingOutput lost =
      stage_->Process({stamp_ + 2 * kStep, black, black, 2}, nullptr);
  ASSERT_EQ(lost.tracking.state, odometry::TrackingState::kLost);
  for (const pipeline::TrackingOutput* output : {&first, &lost}) {
    const pipeline::FrameRecord record = stage_->RecordFrame(*output, stamp_, nullptr);
    EXPECT_TRUE(record.on_map);
    EXPECT_FALSE(record.T_map_camera.has_value());
  }
}

TEST_F(TrackingStageTest, PairsPassedOverTellTheTrackerHowFarApartItsFramesAre) {
  ASSERT_TRUE(Next().tracked);
  arrival_ += 3;  // three pairs the driver had no time for
  const pipeline::InputMonitor::Verdict verdict =
      stage_->input().CheckPair(stamp_ + 4 * kStep, sequence_.LoadStereoPair(7).left,
                                sequence_.LoadStereoPair(7).right, ++arrival_);
  EXPECT_TRUE(verdict.track);
  EXPECT_EQ(verdict.frames_skipped, 3);
}

// A driver that reads the calibration from camera_info makes the stage before it knows the
// camera: every pair until then is refused and counted, and what the other stages announced
// meanwhile (a mode, a loaded map) holds once it is calibrated.
TEST_F(TrackingStageTest, AStageCalibratedLaterCountsThePairsBeforeAndKeepsWhatItWasTold) {
  pipeline::FrontEndOptions options;
  options.tracker.parallel = false;
  options.place_features = options.features;
  pipeline::TrackingStage stage(options, pipeline::InputMonitorOptions(),
                                relocalization::RelocalizerOptions(), [] { return 0.0; });
  EXPECT_FALSE(stage.calibrated());
  EXPECT_THROW(stage.camera(), std::logic_error);
  const datasets::StereoImages images = sequence_.LoadStereoPair(0);
  for (std::uint64_t arrival = 1; arrival <= 3; ++arrival) {
    const pipeline::TrackingOutput refused =
        stage.Process({stamp_ + arrival * kStep, images.left, images.right, arrival}, &map_);
    EXPECT_FALSE(refused.tracked);
    EXPECT_TRUE(HasEvent(refused.events, InputEvent::Kind::kUncalibrated, "no calibration yet"));
  }
  EXPECT_EQ(stage.input().counts().refused, 3u);
  // Told before its camera is known: localization mode, and a map numbered up to 40 / 5000.
  stage.SetMode(pipeline::SlamMode::kLocalization, false);
  stage.OnMapLoaded({12, 40, 5000});
  const Eigen::Isometry3d mounting(Eigen::Translation3d(0.1, 0.0, 0.3));
  stage.Calibrate(rectifier_, mounting);
  EXPECT_THROW(stage.Calibrate(rectifier_), std::logic_error);
  EXPECT_EQ(stage.camera().size, cv::Size(752, 480));
  EXPECT_EQ(stage.policy().mode(), pipeline::SlamMode::kLocalization);
  const pipeline::TrackingOutput first =
      stage.Process({stamp_ + 4 * kStep, images.left, images.right, 4}, &map_);
  ASSERT_TRUE(first.tracked);
  ASSERT_TRUE(first.tracking.keyframe.has_value());
  EXPECT_EQ(first.tracking.keyframe->id, 40) << "numbered above the loaded map's keyframes";
  int points = 0;
  for (const std::int64_t id : first.tracking.keyframe->map_point_ids) {
    if (id < 0) continue;
    EXPECT_GE(id, 5000);
    ++points;
  }
  EXPECT_GT(points, 50) << "the first keyframe's stereo points";
  EXPECT_TRUE(first.tracking.T_world_camera.isApprox(mounting, 1e-9))
      << "the first frame is at the mounting given with the calibration";
  EXPECT_EQ(stage.input().counts().tracked, 1u);
  EXPECT_EQ(stage.input().counts().refused, 3u);
}

// The image callbacks' side of the monitor, with the wall times a driver gives it.
TEST(InputMonitor, ACameraThatDropsOutIsNamedOnlyWhileTheOtherStreams) {
  pipeline::InputMonitor monitor(pipeline::InputMonitorOptions(), cv::Size(752, 480));
  double now = 100.0;
  for (int i = 0; i < 10; ++i, now += 0.05) {  // pairs
    EXPECT_TRUE(monitor.OnImage(0, now).empty());
    EXPECT_TRUE(monitor.OnImage(1, now).empty());
    EXPECT_TRUE(monitor.OnPair(now).empty());
  }
  // The right camera stops; left images go on for 1.5 s.
  const double right_stopped = now - 0.05;
  std::vector<InputEvent> events;
  for (int i = 0; i < 30; ++i, now += 0.05) {
    for (const InputEvent& event : monitor.OnImage(0, now)) events.push_back(event);
    if (now - right_stopped < 1.0) {
      EXPECT_TRUE(events.empty()) << "not before a second";
    }
  }
  EXPECT_TRUE(HasEvent(events, InputEvent::Kind::kDropout, "no right images for 1."));
  monitor.OnImage(1, now);
  EXPECT_TRUE(HasEvent(monitor.OnPair(now), InputEvent::Kind::kPairsAgain, "arrive again"));

  // Both cameras pause for ten minutes (a bag played again later): no dropout is claimed when
  // one of them comes back a moment before the other.
  now += 600.0;
  EXPECT_TRUE(monitor.OnImage(0, now).empty());
  EXPECT_TRUE(monitor.OnImage(1, now + 0.001).empty());
}

TEST(InputMonitor, ImagesThatDoNotPairUpAreNamedAndCountsInEitherOrderAreNot) {
  pipeline::InputMonitorOptions options;
  options.unpaired_limit = 10;
  pipeline::InputMonitor monitor(options, cv::Size(752, 480));
  // A pair counted before its images (another callback's order): never "unpaired".
  for (int i = 0; i < 40; ++i) {
    monitor.OnPair(i * 0.05);
    EXPECT_TRUE(monitor.OnImage(0, i * 0.05).empty());
    EXPECT_TRUE(monitor.OnImage(1, i * 0.05).empty());
  }
  // Stamps that never match: images without pairs.
  std::vector<InputEvent> events;
  for (int i = 40; i < 60; ++i) {
    for (const InputEvent& e : monitor.OnImage(0, i * 0.05)) events.push_back(e);
    for (const InputEvent& e : monitor.OnImage(1, i * 0.05)) events.push_back(e);
  }
  EXPECT_TRUE(HasEvent(events, InputEvent::Kind::kUnsynchronised, "do not synchronise (60 left"));
}

TEST(InputMonitor, SkippedPairsAreReportedAtMostOnceASecond) {
  pipeline::InputMonitor monitor(pipeline::InputMonitorOptions(), cv::Size(752, 480));
  EXPECT_FALSE(monitor.SkipReport(10.0, 8.0).has_value()) << "nothing skipped";
  monitor.CountSkipped(3);
  const std::optional<InputEvent> first = monitor.SkipReport(10.0, 80.0);
  ASSERT_TRUE(first.has_value());
  EXPECT_NE(first->message.find("skipped 3 stereo pair(s) in the last second"), std::string::npos);
  EXPECT_NE(first->message.find("(80 ms for its last pair)"), std::string::npos);
  monitor.CountSkipped(2);
  EXPECT_FALSE(monitor.SkipReport(10.5, 80.0).has_value()) << "within the second";
  EXPECT_DOUBLE_EQ(monitor.NextSkipReport(), 11.0);
  const std::optional<InputEvent> second = monitor.SkipReport(11.0, 80.0);
  ASSERT_TRUE(second.has_value());
  EXPECT_NE(second->message.find("skipped 2 stereo pair(s)"), std::string::npos);
  EXPECT_NE(second->message.find("5 skipped in all"), std::string::npos);
  EXPECT_EQ(monitor.counts().skipped, 5u);
}

}  // namespace
}  // namespace stereo_fabmap_slam::test
