// Feeds the StereoTracker (launched by bad_input.test) real V101 frames interleaved with bad
// input, and checks which frames produce odometry: converted colour does, unsupported encodings,
// wrong sizes and unpaired images do not, time going backwards resets, blank images lose
// tracking, and real frames afterwards are tracked again: nothing crashes.
#include <mutex>
#include <set>
#include <string>
#include <vector>

#include <cv_bridge/cv_bridge.h>
#include <gtest/gtest.h>
#include <nav_msgs/Odometry.h>
#include <ros/ros.h>
#include <rosgraph_msgs/Log.h>
#include <sensor_msgs/image_encodings.h>
#include <opencv2/imgproc.hpp>

#include "ros_conversions.h"
#include "stereo_fabmap_slam/datasets/euroc_sequence.h"
#include "test_support.h"

namespace stereo_fabmap_slam::test {
namespace {

class BadInputTest : public ::testing::Test {
 protected:
  BadInputTest()
      : sequence_(datasets::EurocSequence::Open(EurocSequencePath("V101_micro"))),
        left_(node_.advertise<sensor_msgs::Image>("/cam0/image_raw", 10)),
        right_(node_.advertise<sensor_msgs::Image>("/cam1/image_raw", 10)),
        odometry_(node_.subscribe<nav_msgs::Odometry>(
            "/odometry", 100, [this](const nav_msgs::OdometryConstPtr& m) {
              std::lock_guard<std::mutex> lock(mutex_);
              stamps_.insert(ros_conversions::ToNanoseconds(m->header.stamp));
            })) {}

  void SetUp() override {
    spinner_.start();
    // Wait until the tracker subscribes to both topics (it loads inside the nodelet manager).
    const ros::WallTime deadline = ros::WallTime::now() + ros::WallDuration(30.0);
    while ((left_.getNumSubscribers() == 0 || right_.getNumSubscribers() == 0 ||
            odometry_.getNumPublishers() == 0) &&
           ros::WallTime::now() < deadline) {
      ros::WallDuration(0.1).sleep();
    }
    ASSERT_GT(left_.getNumSubscribers(), 0u) << "tracker never subscribed";
  }

  sensor_msgs::ImagePtr Message(const cv::Mat& image, const std::string& encoding,
                                std::int64_t stamp_ns, const std::string& frame) {
    std_msgs::Header header;
    header.stamp = ros_conversions::ToRosTime(stamp_ns);
    header.frame_id = frame;
    return cv_bridge::CvImage(header, encoding, image).toImageMsg();
  }

  // Publishes a pair and gives the tracker time to process it.
  void Send(const cv::Mat& left, const cv::Mat& right, const std::string& encoding,
            std::int64_t stamp_ns, bool send_right = true) {
    left_.publish(Message(left, encoding, stamp_ns, "cam0"));
    if (send_right) right_.publish(Message(right, encoding, stamp_ns, "cam1"));
    ros::WallDuration(0.15).sleep();
  }

  void SendReal(std::size_t frame, std::int64_t stamp_ns) {
    const datasets::StereoImages images = sequence_.LoadStereoPair(frame);
    Send(images.left, images.right, sensor_msgs::image_encodings::MONO8, stamp_ns);
  }

  // Whether a log message of the graph (/rosout) contained `text`.
  bool Logged(const std::string& text) {
    std::lock_guard<std::mutex> lock(mutex_);
    for (const std::string& message : log_) {
      if (message.find(text) != std::string::npos) return true;
    }
    return false;
  }

  bool HasOdometry(std::int64_t stamp_ns) {
    std::lock_guard<std::mutex> lock(mutex_);
    return stamps_.count(stamp_ns) > 0;
  }

  datasets::EurocSequence sequence_;
  ros::NodeHandle node_;
  ros::Publisher left_, right_;
  ros::Subscriber odometry_;
  ros::Subscriber log_subscriber_ = node_.subscribe<rosgraph_msgs::Log>(
      "/rosout", 100, [this](const rosgraph_msgs::LogConstPtr& m) {
        std::lock_guard<std::mutex> lock(mutex_);
        log_.push_back(m->msg);
      });
  ros::AsyncSpinner spinner_{1};
  std::mutex mutex_;
  std::set<std::int64_t> stamps_;
  std::vector<std::string> log_;
};

TEST_F(BadInputTest, WarnsSkipsAndKeepsTracking) {
  const std::int64_t t0 = sequence_.frames()[0].timestamp_ns;
  const std::int64_t step = 50'000'000;  // 20 Hz
  std::int64_t t = t0;
  for (std::size_t i = 0; i < 5; ++i, t += step) SendReal(i, t);
  EXPECT_TRUE(HasOdometry(t - step)) << "real frames must be tracked";

  // Colour: converted to mono8 and tracked.
  const datasets::StereoImages frame5 = sequence_.LoadStereoPair(5);
  cv::Mat left_bgr, right_bgr;
  cv::cvtColor(frame5.left, left_bgr, cv::COLOR_GRAY2BGR);
  cv::cvtColor(frame5.right, right_bgr, cv::COLOR_GRAY2BGR);
  Send(left_bgr, right_bgr, sensor_msgs::image_encodings::BGR8, t);
  EXPECT_TRUE(HasOdometry(t)) << "bgr8 must be converted";
  t += step;

  // Unsupported encoding (float depth-like images): skipped.
  cv::Mat left_float, right_float;
  frame5.left.convertTo(left_float, CV_32FC1);
  frame5.right.convertTo(right_float, CV_32FC1);
  Send(left_float, right_float, sensor_msgs::image_encodings::TYPE_32FC1, t);
  EXPECT_FALSE(HasOdometry(t));
  t += step;

  // A malformed image (half its data missing): skipped, and said so, not called an encoding.
  {
    sensor_msgs::ImagePtr broken =
        Message(frame5.left, sensor_msgs::image_encodings::MONO8, t, "cam0");
    broken->data.resize(broken->data.size() / 2);
    left_.publish(broken);
    right_.publish(Message(frame5.right, sensor_msgs::image_encodings::MONO8, t, "cam1"));
    ros::WallDuration(0.3).sleep();
    EXPECT_FALSE(HasOdometry(t));
    EXPECT_TRUE(Logged("malformed image on left/image_raw: 180480 bytes of data for 480 rows"));
    EXPECT_FALSE(Logged("unsupported image encoding (mono8"));
    t += step;
  }

  // A size the calibration does not describe: skipped.
  cv::Mat small_left, small_right;
  cv::resize(frame5.left, small_left, cv::Size(376, 240));
  cv::resize(frame5.right, small_right, cv::Size(376, 240));
  Send(small_left, small_right, sensor_msgs::image_encodings::MONO8, t);
  EXPECT_FALSE(HasOdometry(t));
  t += step;

  // The right camera drops out (12 left images, 1.8 s without a right one): nothing to track,
  // and a warning that says so.
  for (int i = 0; i < 12; ++i, t += step) {
    Send(frame5.left, frame5.right, sensor_msgs::image_encodings::MONO8, t, /*send_right=*/false);
    EXPECT_FALSE(HasOdometry(t));
  }
  EXPECT_TRUE(Logged("no right images for")) << "a dropout is named as such";

  // Blank images: no features, tracking lost, no odometry.
  const cv::Mat black(480, 752, CV_8UC1, cv::Scalar(0));
  Send(black, black, sensor_msgs::image_encodings::MONO8, t);
  EXPECT_FALSE(HasOdometry(t));
  t += step;

  // Real frames again: a new map, tracked.
  for (std::size_t i = 6; i < 10; ++i, t += step) SendReal(i, t);
  EXPECT_TRUE(HasOdometry(t - step)) << "tracking must resume after bad input";
  EXPECT_TRUE(Logged("stereo pairs arrive again"));

  // A frozen camera: frame 10 four times under new stamps. The first is tracked, the repeats
  // skipped with a warning, and the next real frame is tracked again.
  const datasets::StereoImages frame10 = sequence_.LoadStereoPair(10);
  std::int64_t first_frozen = t;
  for (int i = 0; i < 4; ++i, t += step) {
    Send(frame10.left, frame10.right, sensor_msgs::image_encodings::MONO8, t);
  }
  EXPECT_TRUE(HasOdometry(first_frozen));
  EXPECT_FALSE(HasOdometry(t - step)) << "a repeated image is not a frame";
  EXPECT_TRUE(Logged("the left and right cameras are frozen: the same image"));
  SendReal(11, t);
  EXPECT_TRUE(HasOdometry(t)) << "tracking goes on when the images change";
  EXPECT_TRUE(Logged("change again after 3 frozen frame(s)"));
  t += step;

  // A gap of 3 s in the images (the camera stood still meanwhile): warned, and tracked across
  // it, the motion model predicting no motion.
  t += 3'000'000'000;
  SendReal(12, t);
  EXPECT_TRUE(Logged("no stereo pairs for 3.0 s")) << "the gap is named";
  EXPECT_TRUE(HasOdometry(t)) << "tracking resumes after a gap";
  t += step;
  SendReal(13, t);
  EXPECT_TRUE(HasOdometry(t));
  t += step;

  // Time going backwards (a looped bag): reset, and tracking goes on from there.
  const std::int64_t looped = t0 - 10 * step;
  for (std::size_t i = 0; i < 3; ++i) SendReal(i, looped + static_cast<std::int64_t>(i) * step);
  EXPECT_TRUE(Logged("time went backwards")) << "the reset is named";
  EXPECT_TRUE(HasOdometry(looped + 2 * step)) << "tracking must resume after time went backwards";
}

}  // namespace
}  // namespace stereo_fabmap_slam::test

int main(int argc, char** argv) {
  testing::InitGoogleTest(&argc, argv);
  ros::init(argc, argv, "bad_input_test");
  return RUN_ALL_TESTS();
}
