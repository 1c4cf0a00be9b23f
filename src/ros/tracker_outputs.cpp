#include "tracker_outputs.h"

#include <chrono>
#include <cmath>
#include <cstdio>

#include <geometry_msgs/TransformStamped.h>
#include <nav_msgs/Odometry.h>
#include <sensor_msgs/Image.h>
#include <stereo_fabmap_slam/Keyframe.h>

#include "ros_conversions.h"
#include "tracking_image.h"

namespace stereo_fabmap_slam::ros_wiring {

TrackerOutputs::TrackerOutputs(ros::NodeHandle& node, const FrameNames& names, bool publish_tf)
    : names_(names),
      publish_tf_(publish_tf),
      odometry_(node.advertise<nav_msgs::Odometry>("odometry", 10)),
      keyframes_(node.advertise<stereo_fabmap_slam::Keyframe>("keyframes", 100)),
      frames_publisher_(node.advertise<stereo_fabmap_slam::TrackedFrame>("tracked_frames", 100)),
      image_(node.advertise<sensor_msgs::Image>("tracking_image", 2)),
      correction_(node.advertise<geometry_msgs::TransformStamped>("map_to_odom_correction", 10)),
      tf_(std::make_unique<tf2_ros::TransformBroadcaster>()),
      static_tf_(std::make_unique<tf2_ros::StaticTransformBroadcaster>()) {
  if (!publish_tf) return;
  // Checked four times a period: a repeat comes at most a quarter period late.
  repeat_timer_ = node.createWallTimer(ros::WallDuration(0.25), [this](const ros::WallTimerEvent&) {
    for (const geometry_msgs::TransformStamped& transform :
         repeater_.Due(ros::WallTime::now().toSec(), ros::Time::now())) {
      tf_->sendTransform(transform);
    }
  });
}

void TrackerOutputs::SetMounting(const Eigen::Isometry3d& T_base_camera) {
  frames_.emplace(T_base_camera);
  odometry_builder_.emplace(*frames_, names_.odom, names_.base);
  if (!publish_tf_) return;
  geometry_msgs::TransformStamped mount;
  mount.header.stamp = ros::Time(0);  // static: valid at every time
  mount.header.frame_id = names_.base;
  mount.child_frame_id = names_.camera;
  mount.transform = ros_conversions::ToTransformMessage(T_base_camera);
  static_tf_->sendTransform(mount);
}

void TrackerOutputs::PublishTracking(const ros::Time& stamp, const pipeline::TrackingOutput& output,
                                     const geometry::StereoCamera& camera,
                                     const cv::Mat& rectified_left) {
  const odometry::TrackingResult& result = output.tracking;
  // Drawn only for someone who looks: a colour copy of every frame is not free.
  if (image_.getNumSubscribers() > 0) {
    image_.publish(
        ros_visualization::TrackingImageMessage(rectified_left, result, stamp, names_.camera));
  }
  if (result.state == odometry::TrackingState::kLost && !result.keyframe) return;  // no pose
  // A loss, or a new segment after one, is not a motion to take a twist from.
  const bool continues = result.state != odometry::TrackingState::kLost &&
                         !(result.keyframe && result.keyframe->starts_new_segment);
  // The stage tracks the camera in odom; the convention's poses are the first camera's.
  const Eigen::Isometry3d T_first_camera = frames_->FromOdom(result.T_world_camera);
  const nav_msgs::Odometry odometry =
      odometry_builder_->Build(stamp, T_first_camera, result.covariance, continues);
  odometry_.publish(odometry);
  if (publish_tf_) {
    geometry_msgs::TransformStamped transform;
    transform.header = odometry.header;
    transform.child_frame_id = names_.base;
    transform.transform = ros_conversions::ToTransformMessage(frames_->BaseInOdom(T_first_camera));
    tf_->sendTransform(transform);
    repeater_.Sent(transform, ros::WallTime::now().toSec());
  }
  if (result.keyframe) {
    stereo_fabmap_slam::Keyframe keyframe =
        ros_conversions::ToKeyframeMessage(*result.keyframe, camera, names_.odom);
    keyframe.header.stamp = stamp;
    keyframes_.publish(keyframe);
  }
}

void TrackerOutputs::PublishFrame(const ros::Time& stamp, stereo_fabmap_slam::TrackedFrame frame) {
  frame.header.stamp = stamp;  // exactly the images' (seconds as a double round it)
  frames_publisher_.publish(frame);
}

void TrackerOutputs::PublishCorrection(const ros::Time& stamp,
                                       const Eigen::Isometry3d& T_map_odom) {
  geometry_msgs::TransformStamped correction;
  correction.header.stamp = stamp;
  correction.header.frame_id = names_.map;
  correction.child_frame_id = names_.odom;
  correction.transform = ros_conversions::ToTransformMessage(T_map_odom);
  correction_.publish(correction);
}

void TrackerOutputs::FillResponse(const pipeline::UserRelocalization& answer,
                                  stereo_fabmap_slam::Relocalize::Response* response) const {
  response->success = answer.success;
  response->message = answer.message;
  response->inliers = answer.inliers;
  response->probability = answer.probability;
  response->time_ms = answer.time_ms;
  response->keyframe_id = answer.keyframe_id;
  if (!answer.success) return;
  response->pose.header.stamp = ros::Time::now();
  response->pose.header.frame_id = names_.map;
  // The base's pose, what a robot's navigation wants.
  response->pose.pose =
      ros_conversions::ToPoseMessage(answer.T_map_camera * frames_->T_base_camera().inverse());
}

std::optional<double> RelocalizeTimeout(double requested) {
  constexpr double kLongest = 60.0;
  if (!std::isfinite(requested) || requested < 0 || requested > kLongest) return std::nullopt;
  return requested > 0 ? requested : 1.0;
}

}  // namespace stereo_fabmap_slam::ros_wiring

namespace stereo_fabmap_slam::ros_wiring {

RelocalizeService::RelocalizeService(ros::NodeHandle& node, const TrackerOutputs& outputs,
                                     Hooks hooks)
    : outputs_(outputs), hooks_(std::move(hooks)) {
  ros::NodeHandle service_node(node);
  service_node.setCallbackQueue(&queue_);
  server_ = service_node.advertiseService("relocalize", &RelocalizeService::OnRelocalize, this);
  // Two threads: while one call waits for its frame, another is told at once that it waits.
  spinner_ = std::make_unique<ros::AsyncSpinner>(2, &queue_);
  spinner_->start();
}

RelocalizeService::~RelocalizeService() {
  spinner_->stop();  // before the members its callback uses
  server_.shutdown();
}

void RelocalizeService::Answer(const pipeline::UserRelocalization& answer) {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    if (!waiting_) return;  // its caller gave up
    answer_ = answer;
  }
  answered_.notify_all();
}

bool RelocalizeService::OnRelocalize(stereo_fabmap_slam::Relocalize::Request& request,
                                     stereo_fabmap_slam::Relocalize::Response& response) {
  response.keyframe_id = -1;
  const std::optional<double> timeout = RelocalizeTimeout(request.timeout);
  if (!timeout) {
    response.message = "timeout must be a number of seconds in [0, 60] (0: 1 s)";
    return true;
  }
  if (hooks_.map_empty()) {
    response.message = "map is empty";
    return true;
  }
  {
    std::lock_guard<std::mutex> lock(mutex_);
    if (waiting_) {
      response.message = "another relocalize call is waiting for a frame";
      return true;
    }
    waiting_ = true;
    answer_.reset();
  }
  // The hooks take the tracking stage's lock, which the tracking thread holds when it answers:
  // never call them holding this one.
  hooks_.ask(request.reanchor);
  std::unique_lock<std::mutex> lock(mutex_);
  const bool answered = answered_.wait_for(lock, std::chrono::duration<double>(*timeout),
                                           [&] { return answer_.has_value(); });
  const std::optional<pipeline::UserRelocalization> answer = answer_;
  waiting_ = false;
  lock.unlock();
  if (!answered) {
    hooks_.cancel();
    char text[96];
    std::snprintf(text, sizeof(text), "no stereo images arrived within %.1f s", *timeout);
    response.message = text;
    return true;
  }
  outputs_.FillResponse(*answer, &response);
  return true;
}

}  // namespace stereo_fabmap_slam::ros_wiring
