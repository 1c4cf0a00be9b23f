// StereoTracker: synchronised raw stereo images in, odometry, tf odom -> camera and keyframes out.
// Everything algorithmic is pipeline::StereoFrontEnd; this file converts and publishes.
#include <atomic>
#include <chrono>
#include <cstdint>
#include <memory>
#include <mutex>
#include <optional>
#include <string>

#include <cv_bridge/cv_bridge.h>
#include <geometry_msgs/TransformStamped.h>
#include <message_filters/subscriber.h>
#include <message_filters/sync_policies/approximate_time.h>
#include <message_filters/sync_policies/exact_time.h>
#include <message_filters/synchronizer.h>
#include <nav_msgs/Odometry.h>
#include <nodelet/nodelet.h>
#include <ros/ros.h>
#include <sensor_msgs/CameraInfo.h>
#include <sensor_msgs/Image.h>
#include <tf2_ros/transform_broadcaster.h>
#include <pluginlib/class_list_macros.hpp>

#include "parameter_reader.h"
#include "ros_conversions.h"
#include "stereo_fabmap_slam/camera/camera_calibration.h"
#include "stereo_fabmap_slam/pipeline/stereo_front_end.h"
#include "stereo_fabmap_slam/place_recognition/place_recognition_options.h"

namespace stereo_fabmap_slam {

class StereoTrackerNodelet : public nodelet::Nodelet {
 private:
  using Image = sensor_msgs::Image;
  using ExactPolicy = message_filters::sync_policies::ExactTime<Image, Image>;
  using ApproximatePolicy = message_filters::sync_policies::ApproximateTime<Image, Image>;
  using InfoPolicy =
      message_filters::sync_policies::ExactTime<sensor_msgs::CameraInfo, sensor_msgs::CameraInfo>;

  void onInit() override;
  void LoadOptions(const ros::NodeHandle& private_node);
  void OnCameraInfo(const sensor_msgs::CameraInfoConstPtr& left,
                    const sensor_msgs::CameraInfoConstPtr& right);
  void OnImages(const sensor_msgs::ImageConstPtr& left, const sensor_msgs::ImageConstPtr& right);
  void OnKeyframeUpdate(const stereo_fabmap_slam::KeyframeUpdateConstPtr& update);
  // Counts images of one side; warns when more go unpaired than the sync queue can hold.
  void OnSingleImage(std::atomic<std::uint64_t>* count);
  void Publish(const ros::Time& stamp, const odometry::TrackingResult& result);

  camera::RectificationOptions rectification_options_;
  pipeline::FrontEndOptions options_;
  std::string odom_frame_, camera_frame_;
  std::mutex mutex_;  // image and update callbacks may run on different manager threads
  std::unique_ptr<pipeline::StereoFrontEnd> front_end_;
  ros::Time last_stamp_;
  int queue_size_ = 10;
  std::atomic<std::uint64_t> left_images_{0}, right_images_{0}, pairs_{0};

  message_filters::Subscriber<Image> left_subscriber_, right_subscriber_;
  message_filters::Subscriber<sensor_msgs::CameraInfo> left_info_subscriber_,
      right_info_subscriber_;
  std::unique_ptr<message_filters::Synchronizer<ExactPolicy>> exact_sync_;
  std::unique_ptr<message_filters::Synchronizer<ApproximatePolicy>> approximate_sync_;
  std::unique_ptr<message_filters::Synchronizer<InfoPolicy>> info_sync_;
  ros::Subscriber update_subscriber_;
  ros::Publisher odometry_publisher_, keyframe_publisher_;
  std::unique_ptr<tf2_ros::TransformBroadcaster> tf_broadcaster_;
};

double SteadyMilliseconds() {
  return std::chrono::duration<double, std::milli>(
             std::chrono::steady_clock::now().time_since_epoch())
      .count();
}

void StereoTrackerNodelet::LoadOptions(const ros::NodeHandle& private_node) {
  // A configuration file first (config/euroc.yaml and its presets), then single private
  // parameters "~<section>/<key>" on top; a bad value stops start-up with its name.
  std::string printed;
  rectification_options_ = ros_parameters::ReadModuleOptions(private_node, rectification_options_);
  printed += ros_parameters::PrintedOptions(rectification_options_);
  options_.ForEachModule([&](auto& options) {
    options = ros_parameters::ReadModuleOptions(private_node, options);
    printed += ros_parameters::PrintedOptions(options);
  });
  // Loop closing needs place descriptors in every keyframe, with place recognition's own key
  // point selection (config/fabmap.yaml).
  if (private_node.param("loop_closing", true)) {
    std::string fabmap_config;
    if (!private_node.getParam("fabmap_config", fabmap_config)) {
      throw std::runtime_error(
          "set ~fabmap_config (e.g. config/fabmap.yaml) or ~loop_closing false");
    }
    options_.place_features =
        place_recognition::LoadPlaceRecognitionOptions(fabmap_config, options_.features).features;
    printed += "place recognition features from " + fabmap_config + "\n";
  }
  NODELET_INFO_STREAM("options in force:\n" << printed);
}

void StereoTrackerNodelet::onInit() {
  ros::NodeHandle& node = getNodeHandle();
  ros::NodeHandle& private_node = getPrivateNodeHandle();
  try {
    LoadOptions(private_node);
  } catch (const std::exception& error) {
    NODELET_FATAL_STREAM("bad configuration: " << error.what());
    throw;
  }
  odom_frame_ = private_node.param<std::string>("odom_frame", "odom");
  camera_frame_ = private_node.param<std::string>("camera_frame", "camera");
  const int queue_size = private_node.param("queue_size", 10);
  queue_size_ = queue_size;
  const bool approximate = private_node.param("approximate_sync", false);
  const bool use_camera_info = private_node.param("use_camera_info", false);

  if (!use_camera_info) {
    std::string calibration_file;
    if (!private_node.getParam("calibration_file", calibration_file)) {
      NODELET_FATAL("set ~calibration_file (e.g. config/euroc_stereo.yaml) or ~use_camera_info");
      throw std::runtime_error("no calibration");
    }
    try {
      const camera::StereoCalibration calibration =
          camera::ReadStereoCalibrationYaml(calibration_file);
      front_end_ = std::make_unique<pipeline::StereoFrontEnd>(
          options_, camera::StereoRectifier::FromCalibration(calibration, rectification_options_),
          SteadyMilliseconds);
    } catch (const std::exception& error) {
      NODELET_FATAL_STREAM("calibration: " << error.what());
      throw;
    }
  } else {
    left_info_subscriber_.subscribe(node, "left/camera_info", queue_size);
    right_info_subscriber_.subscribe(node, "right/camera_info", queue_size);
    info_sync_ = std::make_unique<message_filters::Synchronizer<InfoPolicy>>(
        InfoPolicy(queue_size), left_info_subscriber_, right_info_subscriber_);
    info_sync_->registerCallback(&StereoTrackerNodelet::OnCameraInfo, this);
  }

  odometry_publisher_ = node.advertise<nav_msgs::Odometry>("odometry", 10);
  keyframe_publisher_ = node.advertise<stereo_fabmap_slam::Keyframe>("keyframes", 100);
  update_subscriber_ =
      node.subscribe("keyframe_updates", 100, &StereoTrackerNodelet::OnKeyframeUpdate, this);
  tf_broadcaster_ = std::make_unique<tf2_ros::TransformBroadcaster>();

  left_subscriber_.subscribe(node, "left/image_raw", queue_size);
  right_subscriber_.subscribe(node, "right/image_raw", queue_size);
  left_subscriber_.registerCallback(
      [this](const sensor_msgs::ImageConstPtr&) { OnSingleImage(&left_images_); });
  right_subscriber_.registerCallback(
      [this](const sensor_msgs::ImageConstPtr&) { OnSingleImage(&right_images_); });
  if (approximate) {
    approximate_sync_ = std::make_unique<message_filters::Synchronizer<ApproximatePolicy>>(
        ApproximatePolicy(queue_size), left_subscriber_, right_subscriber_);
    approximate_sync_->registerCallback(&StereoTrackerNodelet::OnImages, this);
  } else {
    exact_sync_ = std::make_unique<message_filters::Synchronizer<ExactPolicy>>(
        ExactPolicy(queue_size), left_subscriber_, right_subscriber_);
    exact_sync_->registerCallback(&StereoTrackerNodelet::OnImages, this);
  }
  NODELET_INFO_STREAM("tracking " << left_subscriber_.getTopic() << " + "
                                  << right_subscriber_.getTopic()
                                  << (approximate ? " (approximate" : " (exact") << " time sync)");
}

void StereoTrackerNodelet::OnCameraInfo(const sensor_msgs::CameraInfoConstPtr& left,
                                        const sensor_msgs::CameraInfoConstPtr& right) {
  std::lock_guard<std::mutex> lock(mutex_);
  if (front_end_) return;  // the first pair defines the rectification
  try {
    front_end_ = std::make_unique<pipeline::StereoFrontEnd>(
        options_,
        ros_conversions::RectifierFromCameraInfo(*left, *right, Eigen::Isometry3d::Identity()),
        SteadyMilliseconds);
    NODELET_INFO("stereo model from camera_info: baseline %.3f m", front_end_->camera().baseline);
  } catch (const std::exception& error) {
    NODELET_WARN_THROTTLE(5, "camera_info pair unusable: %s", error.what());
  }
}

void StereoTrackerNodelet::OnSingleImage(std::atomic<std::uint64_t>* count) {
  const std::uint64_t unpaired = ++*count - pairs_.load();
  if (unpaired > static_cast<std::uint64_t>(queue_size_)) {
    NODELET_WARN_THROTTLE(5,
                          "left/right images do not synchronise (%lu left, %lu right, %lu pairs); "
                          "stamps must be equal, or set ~approximate_sync",
                          static_cast<unsigned long>(left_images_.load()),
                          static_cast<unsigned long>(right_images_.load()),
                          static_cast<unsigned long>(pairs_.load()));
  }
}

void StereoTrackerNodelet::OnImages(const sensor_msgs::ImageConstPtr& left_message,
                                    const sensor_msgs::ImageConstPtr& right_message) {
  ++pairs_;
  std::lock_guard<std::mutex> lock(mutex_);
  if (!front_end_) {
    NODELET_WARN_THROTTLE(5, "no calibration yet (waiting for camera_info); frame skipped");
    return;
  }
  cv_bridge::CvImageConstPtr left, right;
  try {
    // Colour images are converted to mono8; encodings cv_bridge cannot convert throw.
    left = cv_bridge::toCvShare(left_message, "mono8");
    right = cv_bridge::toCvShare(right_message, "mono8");
  } catch (const cv_bridge::Exception& error) {
    NODELET_WARN_THROTTLE(5, "unsupported image encoding (%s / %s): %s; frame skipped",
                          left_message->encoding.c_str(), right_message->encoding.c_str(),
                          error.what());
    return;
  }
  const cv::Size expected = front_end_->camera().size;
  if (left->image.size() != expected || right->image.size() != expected) {
    NODELET_WARN_THROTTLE(
        5, "image size %dx%d / %dx%d differs from the calibration's %dx%d; frame skipped",
        left->image.cols, left->image.rows, right->image.cols, right->image.rows, expected.width,
        expected.height);
    return;
  }
  const ros::Time stamp = left_message->header.stamp;
  if (!last_stamp_.isZero() && stamp <= last_stamp_) {
    NODELET_WARN("time went backwards (%.3f after %.3f; a looped bag?): tracking reset",
                 stamp.toSec(), last_stamp_.toSec());
    front_end_->Reset();
  }
  last_stamp_ = stamp;
  try {
    const pipeline::FrontEndOutput output =
        front_end_->Process(stamp.toSec(), left->image, right->image);
    if (output.tracking.state == odometry::TrackingState::kLost) {
      NODELET_WARN_THROTTLE(2, "tracking lost: %s", output.tracking.reason.c_str());
    }
    Publish(stamp, output.tracking);
  } catch (const std::exception& error) {
    NODELET_WARN_THROTTLE(5, "frame skipped: %s", error.what());
  }
}

void StereoTrackerNodelet::Publish(const ros::Time& stamp, const odometry::TrackingResult& result) {
  if (result.state == odometry::TrackingState::kLost && !result.keyframe)
    return;  // no pose to give
  const geometry_msgs::Pose pose = ros_conversions::ToPoseMessage(result.T_world_camera);
  nav_msgs::Odometry odometry;
  odometry.header.stamp = stamp;
  odometry.header.frame_id = odom_frame_;
  odometry.child_frame_id = camera_frame_;
  odometry.pose.pose = pose;
  odometry_publisher_.publish(odometry);

  geometry_msgs::TransformStamped transform;
  transform.header = odometry.header;
  transform.child_frame_id = camera_frame_;
  transform.transform = ros_conversions::ToTransformMessage(result.T_world_camera);
  tf_broadcaster_->sendTransform(transform);

  if (result.keyframe) {
    keyframe_publisher_.publish(
        ros_conversions::ToKeyframeMessage(*result.keyframe, front_end_->camera(), odom_frame_));
  }
}

void StereoTrackerNodelet::OnKeyframeUpdate(
    const stereo_fabmap_slam::KeyframeUpdateConstPtr& message) {
  std::lock_guard<std::mutex> lock(mutex_);
  if (!front_end_) return;
  try {
    front_end_->ApplyUpdate(ros_conversions::FromKeyframeUpdateMessage(*message));
  } catch (const std::exception& error) {
    NODELET_WARN_THROTTLE(5, "keyframe update ignored: %s", error.what());
  }
}

}  // namespace stereo_fabmap_slam

PLUGINLIB_EXPORT_CLASS(stereo_fabmap_slam::StereoTrackerNodelet, nodelet::Nodelet)
