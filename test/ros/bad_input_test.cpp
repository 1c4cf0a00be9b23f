// The StereoTracker's wiring of its input faults (launched by bad_input.test): one case per fault,
// on real V101 frames. What each fault means is the tracking stage's and is tested without ROS
// (tracking_stage_test); here every pair is followed to its tracked_frames message (no sleeping
// and hoping), the odometry of tracked frames, and the warning the user reads: converted colour
// is tracked; unsupported encodings, malformed images, wrong sizes, unpaired and repeated
// (frozen) images are not; a gap and time going backwards are named; and in every test real
// frames after the fault are tracked again. The tests share the one tracker the launch starts
// and go on from the stamps the one before left; none depends on another's fault or on their
// order (each sees only its own frames and messages, and no stamp is sent twice:
// GTEST_SHUFFLE=1 runs them in another order).
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <set>
#include <string>
#include <vector>

#include <cv_bridge/cv_bridge.h>
#include <gtest/gtest.h>
#include <nav_msgs/Odometry.h>
#include <ros/ros.h>
#include <rosgraph_msgs/Log.h>
#include <sensor_msgs/image_encodings.h>
#include <stereo_fabmap_slam/TrackedFrame.h>
#include <opencv2/imgproc.hpp>

#include "ros_conversions.h"
#include "stereo_fabmap_slam/datasets/euroc_sequence.h"
#include "test_support.h"

namespace stereo_fabmap_slam::test {
namespace {

// The test's side of the graph: image publishers, odometry and /rosout subscribers, and where
// the stream of stamps and frames goes on from. One for all the tests, as the launched tracker
// is one: subscribing anew in each test would lose what arrives before the connection stands.
class Graph {
 public:
  Graph()
      : left_(node_.advertise<sensor_msgs::Image>("/cam0/image_raw", 10)),
        right_(node_.advertise<sensor_msgs::Image>("/cam1/image_raw", 10)),
        odometry_(node_.subscribe<nav_msgs::Odometry>(
            "/odometry", 100,
            [this](const nav_msgs::OdometryConstPtr& m) {
              std::lock_guard<std::mutex> lock(mutex_);
              stamps_.insert(ros_conversions::ToNanoseconds(m->header.stamp));
            })),
        frames_(node_.subscribe<stereo_fabmap_slam::TrackedFrame>(
            "/tracked_frames", 100,
            [this](const stereo_fabmap_slam::TrackedFrameConstPtr& m) {
              std::lock_guard<std::mutex> lock(mutex_);
              frames_seen_[ros_conversions::ToNanoseconds(m->header.stamp)] = *m;
            })),
        log_subscriber_(node_.subscribe<rosgraph_msgs::Log>(
            "/rosout", 100, [this](const rosgraph_msgs::LogConstPtr& m) {
              std::lock_guard<std::mutex> lock(mutex_);
              log_.push_back(m->msg);
            })) {
    spinner_.start();
  }

  // Waits until the tracker (loaded inside the nodelet manager) subscribes and publishes.
  bool Connected() {
    const ros::WallTime deadline = ros::WallTime::now() + ros::WallDuration(30.0);
    while ((left_.getNumSubscribers() == 0 || right_.getNumSubscribers() == 0 ||
            odometry_.getNumPublishers() == 0) &&
           ros::WallTime::now() < deadline) {
      ros::WallDuration(0.1).sleep();
    }
    return left_.getNumSubscribers() > 0 && right_.getNumSubscribers() > 0;
  }

  void Publish(const sensor_msgs::ImagePtr& left, const sensor_msgs::ImagePtr& right) {
    if (left) left_.publish(left);
    if (right) right_.publish(right);
  }

  // Whether a log message of the graph (/rosout) since the last Forget contains `text`,
  // waiting up to 5 s for it (/rosout comes on its own connection, behind the pairs).
  bool Logged(const std::string& text, double wait = 5.0) {
    return Within(wait, [&] {
      for (const std::string& message : log_) {
        if (message.find(text) != std::string::npos) return true;
      }
      return false;
    });
  }

  // The tracker's account of the pair at `stamp_ns`, waiting up to 10 s for it: every pair it
  // takes gets one, tracked or refused.
  std::optional<stereo_fabmap_slam::TrackedFrame> Frame(std::int64_t stamp_ns) {
    std::optional<stereo_fabmap_slam::TrackedFrame> frame;
    Within(10.0, [&] {
      const auto it = frames_seen_.find(stamp_ns);
      if (it != frames_seen_.end()) frame = it->second;
      return frame.has_value();
    });
    return frame;
  }

  // Forgets the messages and frames seen so far: a test checks only its own.
  void Forget() {
    std::lock_guard<std::mutex> lock(mutex_);
    log_.clear();
    stamps_.clear();
    frames_seen_.clear();
  }

  // Whether odometry came for the stamp, waiting up to `wait` s (0: as things are).
  bool HasOdometry(std::int64_t stamp_ns, double wait = 5.0) {
    return Within(wait, [&] { return stamps_.count(stamp_ns) > 0; });
  }

  std::int64_t first_stamp = 0;  // of the stream; no stamp below it is sent but by a reset
  std::int64_t next_stamp = 0;
  std::size_t next_frame = 0;

 private:
  // Polls `condition` (under the lock) until it holds or `seconds` have passed.
  template <typename Condition>
  bool Within(double seconds, Condition condition) {
    const ros::WallTime deadline = ros::WallTime::now() + ros::WallDuration(seconds);
    while (true) {
      {
        std::lock_guard<std::mutex> lock(mutex_);
        if (condition()) return true;
      }
      if (ros::WallTime::now() > deadline) return false;
      ros::WallDuration(0.01).sleep();
    }
  }

  // What the callbacks fill comes first and the spinner last: destroyed in reverse, the spinner
  // stops before anything a callback touches is gone.
  std::mutex mutex_;
  std::set<std::int64_t> stamps_;
  std::map<std::int64_t, stereo_fabmap_slam::TrackedFrame> frames_seen_;
  std::vector<std::string> log_;
  ros::NodeHandle node_;
  ros::Publisher left_, right_;
  ros::Subscriber odometry_, frames_, log_subscriber_;
  ros::AsyncSpinner spinner_{1};
};

class BadInputTest : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    graph_ = std::make_unique<Graph>();
    graph_->first_stamp =
        datasets::EurocSequence::Open(EurocSequencePath("V101_micro")).frames()[0].timestamp_ns;
    graph_->next_stamp = graph_->first_stamp;
  }
  static void TearDownTestSuite() { graph_.reset(); }

  BadInputTest() : sequence_(datasets::EurocSequence::Open(EurocSequencePath("V101_micro"))) {}

  void SetUp() override {
    ASSERT_TRUE(graph_->Connected()) << "tracker never subscribed";
    graph_->Forget();  // each test checks the messages and frames of its own fault
  }

  static sensor_msgs::ImagePtr Message(const cv::Mat& image, const std::string& encoding,
                                       std::int64_t stamp_ns, const std::string& frame) {
    std_msgs::Header header;
    header.stamp = ros_conversions::ToRosTime(stamp_ns);
    header.frame_id = frame;
    return cv_bridge::CvImage(header, encoding, image).toImageMsg();
  }

  // Publishes a pair and returns the tracker's account of it; one camera's image alone (no pair
  // to account for) is followed by a camera's period of 0.15 s.
  static std::optional<stereo_fabmap_slam::TrackedFrame> Send(
      const cv::Mat& left, const cv::Mat& right, const std::string& encoding, std::int64_t stamp_ns,
      bool send_left = true, bool send_right = true) {
    graph_->Publish(send_left ? Message(left, encoding, stamp_ns, "cam0") : nullptr,
                    send_right ? Message(right, encoding, stamp_ns, "cam1") : nullptr);
    if (send_left && send_right) return graph_->Frame(stamp_ns);
    ros::WallDuration(0.15).sleep();
    return std::nullopt;
  }

  // Whether the pair was tracked to a pose (what odometry is published for).
  static bool Tracked(const std::optional<stereo_fabmap_slam::TrackedFrame>& frame) {
    return frame && frame->tracked && frame->state != stereo_fabmap_slam::TrackedFrame::LOST;
  }
  static bool Refused(const std::optional<stereo_fabmap_slam::TrackedFrame>& frame) {
    return frame && !frame->tracked;
  }

  // The next stamp of the stream the tests share: 20 Hz, as the camera's.
  static std::int64_t NextStamp() {
    const std::int64_t stamp = graph_->next_stamp;
    graph_->next_stamp += kStep;
    return stamp;
  }

  // The next real frames of V101_micro (a hovering camera: any of them follows any other),
  // under the next stamps; whether the last of them got odometry.
  bool TrackRealFrames(int count) {
    std::optional<stereo_fabmap_slam::TrackedFrame> last;
    for (int i = 0; i < count; ++i) {
      const datasets::StereoImages images =
          sequence_.LoadStereoPair(graph_->next_frame++ % sequence_.frames().size());
      last = Send(images.left, images.right, sensor_msgs::image_encodings::MONO8, NextStamp());
    }
    return Tracked(last);
  }

  // One camera ("left" or "right") drops out for 1.8 s (12 images of the other): nothing to
  // track, a warning that names the camera, and tracking when pairs arrive again.
  void CheckCameraDroppingOut(const std::string& camera) {
    const datasets::StereoImages pair = SomePair();
    for (int i = 0; i < 12; ++i) {
      const std::int64_t t = NextStamp();
      Send(pair.left, pair.right, sensor_msgs::image_encodings::MONO8, t,
           /*send_left=*/camera != "left", /*send_right=*/camera != "right");
      EXPECT_FALSE(HasOdometry(t, 0.0));
    }
    EXPECT_TRUE(Logged("no " + camera + " images for")) << "a dropout is named as such";
    EXPECT_TRUE(TrackRealFrames(4)) << "tracking must resume when pairs arrive again";
    EXPECT_TRUE(Logged("stereo pairs arrive again"));
  }

  // A pair of V101_micro to corrupt.
  datasets::StereoImages SomePair() { return sequence_.LoadStereoPair(5); }

  // `wait` 0 for what must not have been said (after what must have, which is later).
  static bool Logged(const std::string& text, double wait = 5.0) {
    return graph_->Logged(text, wait);
  }
  static bool HasOdometry(std::int64_t stamp_ns, double wait = 5.0) {
    return graph_->HasOdometry(stamp_ns, wait);
  }

  static constexpr std::int64_t kStep = 50'000'000;  // 20 Hz
  static std::unique_ptr<Graph> graph_;
  datasets::EurocSequence sequence_;
};

std::unique_ptr<Graph> BadInputTest::graph_;

TEST_F(BadInputTest, RealFramesAreTracked) {
  const std::int64_t last = graph_->next_stamp + 4 * kStep;
  EXPECT_TRUE(TrackRealFrames(5)) << "real frames must be tracked";
  EXPECT_TRUE(HasOdometry(last)) << "and their odometry published";
}

TEST_F(BadInputTest, ColourIsConvertedAndTracked) {
  const datasets::StereoImages pair = sequence_.LoadStereoPair(graph_->next_frame++);
  cv::Mat left_bgr, right_bgr;
  cv::cvtColor(pair.left, left_bgr, cv::COLOR_GRAY2BGR);
  cv::cvtColor(pair.right, right_bgr, cv::COLOR_GRAY2BGR);
  EXPECT_TRUE(Tracked(Send(left_bgr, right_bgr, sensor_msgs::image_encodings::BGR8, NextStamp())))
      << "bgr8 must be converted";
}

TEST_F(BadInputTest, UnsupportedEncodingIsSkippedAndNamed) {
  const datasets::StereoImages pair = SomePair();
  cv::Mat left_float, right_float;
  pair.left.convertTo(left_float, CV_32FC1);
  pair.right.convertTo(right_float, CV_32FC1);
  EXPECT_TRUE(Refused(
      Send(left_float, right_float, sensor_msgs::image_encodings::TYPE_32FC1, NextStamp())));
  EXPECT_TRUE(Logged("unsupported image encoding (32FC1 / 32FC1)"));
  EXPECT_TRUE(TrackRealFrames(2)) << "tracking goes on after the skipped pair";
}

TEST_F(BadInputTest, MalformedImageIsSkippedAndNamed) {
  const datasets::StereoImages pair = SomePair();
  const std::int64_t t = NextStamp();
  sensor_msgs::ImagePtr broken = Message(pair.left, sensor_msgs::image_encodings::MONO8, t, "cam0");
  broken->data.resize(broken->data.size() / 2);  // half its data missing
  graph_->Publish(broken, Message(pair.right, sensor_msgs::image_encodings::MONO8, t, "cam1"));
  EXPECT_TRUE(Refused(graph_->Frame(t)));
  EXPECT_TRUE(Logged("malformed image on left/image_raw: 180480 bytes of data for 480 rows"));
  EXPECT_FALSE(Logged("unsupported image encoding (mono8", 0.0)) << "not called an encoding";
  EXPECT_TRUE(TrackRealFrames(2)) << "tracking goes on after the skipped pair";
}

TEST_F(BadInputTest, SizeOtherThanTheCalibrationsIsSkippedAndNamed) {
  const datasets::StereoImages pair = SomePair();
  cv::Mat small_left, small_right;
  cv::resize(pair.left, small_left, cv::Size(376, 240));
  cv::resize(pair.right, small_right, cv::Size(376, 240));
  EXPECT_TRUE(
      Refused(Send(small_left, small_right, sensor_msgs::image_encodings::MONO8, NextStamp())));
  EXPECT_TRUE(Logged("image size 376x240 / 376x240 differs from the calibration's 752x480"));
  EXPECT_TRUE(TrackRealFrames(2)) << "tracking goes on after the skipped pair";
}

TEST_F(BadInputTest, RightCameraDroppingOutIsNamedAndTrackingResumes) {
  CheckCameraDroppingOut("right");
}

TEST_F(BadInputTest, LeftCameraDroppingOutIsNamedAndTrackingResumes) {
  CheckCameraDroppingOut("left");
}

TEST_F(BadInputTest, BlankImagesLoseTrackingAndRealFramesStartAgain) {
  const cv::Mat black(480, 752, CV_8UC1, cv::Scalar(0));
  const std::optional<stereo_fabmap_slam::TrackedFrame> blank =
      Send(black, black, sensor_msgs::image_encodings::MONO8, NextStamp());
  ASSERT_TRUE(blank.has_value());
  EXPECT_TRUE(blank->tracked) << "blank images are input, not a fault of it";
  EXPECT_FALSE(Tracked(blank)) << "no features, no pose";
  EXPECT_TRUE(Logged("tracking lost:"));
  EXPECT_TRUE(TrackRealFrames(4)) << "tracking must resume after blank images";
}

// A frozen camera: one frame four times under new stamps. The first is tracked, the repeats
// skipped with a warning, and the next real frame is tracked again.
TEST_F(BadInputTest, FrozenCameraIsNamedAndItsRepeatsSkipped) {
  const datasets::StereoImages frozen = sequence_.LoadStereoPair(graph_->next_frame++);
  EXPECT_TRUE(
      Tracked(Send(frozen.left, frozen.right, sensor_msgs::image_encodings::MONO8, NextStamp())));
  for (int i = 0; i < 3; ++i) {
    EXPECT_TRUE(
        Refused(Send(frozen.left, frozen.right, sensor_msgs::image_encodings::MONO8, NextStamp())))
        << "a repeated image is not a frame";
  }
  EXPECT_TRUE(Logged("the left and right cameras are frozen: the same image"));
  EXPECT_TRUE(TrackRealFrames(1)) << "tracking goes on when the images change";
  EXPECT_TRUE(Logged("change again after 3 frozen frame(s)"));
}

// A gap of 3 s in the images (the camera stood still meanwhile): named, and tracked across it,
// the motion model predicting no motion.
TEST_F(BadInputTest, GapIsNamedAndTrackedAcross) {
  graph_->next_stamp += 3'000'000'000 - kStep;
  EXPECT_TRUE(TrackRealFrames(1)) << "tracking resumes after a gap";
  EXPECT_TRUE(Logged("no stereo pairs for 3.0 s")) << "the gap is named";
  EXPECT_TRUE(TrackRealFrames(1));
}

// Time going backwards (a looped bag): reset, named, and tracking goes on from there, upward from
// the earlier stamps. 50 s below the stream's first stamp: below every stamp sent, whichever
// tests ran before, and more than all the tests send after it.
TEST_F(BadInputTest, TimeGoingBackwardsResetsAndTrackingGoesOn) {
  EXPECT_TRUE(TrackRealFrames(2)) << "frames to go back from, whichever tests ran before";
  graph_->next_stamp = graph_->first_stamp - 1000 * kStep;
  EXPECT_TRUE(TrackRealFrames(3)) << "tracking must resume after time went backwards";
  EXPECT_TRUE(Logged("time went backwards")) << "the reset is named";
}

}  // namespace
}  // namespace stereo_fabmap_slam::test

int main(int argc, char** argv) {
  testing::InitGoogleTest(&argc, argv);
  ros::init(argc, argv, "bad_input_test");
  return RUN_ALL_TESTS();
}
