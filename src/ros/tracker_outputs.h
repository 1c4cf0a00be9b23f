#pragma once

// What the StereoTracker publishes, in REP-105's frames: odometry (the base in odom), tf
// odom -> base_link and the camera's mounting, keyframes, tracked_frames, the tracking image and
// localization's map -> odom. The tracking stage tracks the camera in odom; this turns its
// output into messages.

#include <condition_variable>
#include <functional>
#include <memory>
#include <mutex>
#include <optional>
#include <string>

#include <ros/callback_queue.h>
#include <ros/node_handle.h>
#include <ros/publisher.h>
#include <ros/service_server.h>
#include <ros/spinner.h>
#include <stereo_fabmap_slam/Relocalize.h>
#include <stereo_fabmap_slam/TrackedFrame.h>
#include <tf2_ros/static_transform_broadcaster.h>
#include <tf2_ros/transform_broadcaster.h>

#include "transform_repeater.h"

#include "base_frame_convention.h"
#include "odometry_message_builder.h"
#include "stereo_fabmap_slam/pipeline/relocalization_policy.h"
#include "stereo_fabmap_slam/pipeline/tracking_stage.h"

namespace stereo_fabmap_slam::ros_wiring {

struct FrameNames {
  std::string map = "map", odom = "odom", base = "base_link", camera = "camera_optical";
};

class TrackerOutputs {
 public:
  // Advertises odometry, keyframes, tracked_frames, tracking_image (and, for localization,
  // map_to_odom_correction) on `node`.
  TrackerOutputs(ros::NodeHandle& node, const FrameNames& names, bool publish_tf);

  // The camera's mounting (T_base_camera of its rectified left camera): the static tf
  // base_link -> camera, and how odometry is carried to the base. Before the first frame.
  void SetMounting(const Eigen::Isometry3d& T_base_camera);
  const Eigen::Isometry3d& T_base_camera() const { return frames_->T_base_camera(); }

  // A tracked frame's odometry and tf (none for a frame without a pose), its keyframe, and the
  // tracking image when someone looks (`rectified_left`: the frame's rectified left image).
  void PublishTracking(const ros::Time& stamp, const pipeline::TrackingOutput& output,
                       const geometry::StereoCamera& camera, const cv::Mat& rectified_left);
  // The pair's account on tracked_frames, under the images' exact stamp.
  void PublishFrame(const ros::Time& stamp, stereo_fabmap_slam::TrackedFrame frame);
  void PublishCorrection(const ros::Time& stamp, const Eigen::Isometry3d& T_map_odom);

  // The relocalize service's answer: the base's pose in map on success.
  void FillResponse(const pipeline::UserRelocalization& answer,
                    stereo_fabmap_slam::Relocalize::Response* response) const;

 private:
  FrameNames names_;
  bool publish_tf_;
  ros::Publisher odometry_, keyframes_, frames_publisher_, image_, correction_;
  std::unique_ptr<tf2_ros::TransformBroadcaster> tf_;
  std::unique_ptr<tf2_ros::StaticTransformBroadcaster> static_tf_;
  TransformRepeater repeater_;  // odom -> base_link after the input stops (the bag ended)
  ros::WallTimer repeat_timer_;
  std::optional<ros_conversions::BaseFrameConvention> frames_;
  std::optional<ros_conversions::OdometryMessageBuilder> odometry_builder_;
};

// The relocalize service's timeout [s] (0: 1 s), or nullopt for one that is not a number of
// seconds in [0, 60]: one call waits at a time, and a caller waiting an hour for images that
// never come would hold the service from everyone else.
std::optional<double> RelocalizeTimeout(double requested);

// The relocalize service: on a queue and thread of its own (a call waits for the next frame,
// which the tracking thread handles meanwhile, and must not hold a thread of the manager's pool),
// one call at a time, answered by the tracking thread (Answer).
class RelocalizeService {
 public:
  struct Hooks {
    std::function<bool()> map_empty;
    std::function<void(bool reanchor)> ask;  // the tracking stage's RequestRelocalization
    std::function<void()> cancel;            // ... and CancelRelocalizationRequest
  };
  RelocalizeService(ros::NodeHandle& node, const TrackerOutputs& outputs, Hooks hooks);
  ~RelocalizeService();
  void Answer(const pipeline::UserRelocalization& answer);

 private:
  bool OnRelocalize(stereo_fabmap_slam::Relocalize::Request& request,
                    stereo_fabmap_slam::Relocalize::Response& response);

  const TrackerOutputs& outputs_;
  Hooks hooks_;
  std::mutex mutex_;
  std::condition_variable answered_;
  bool waiting_ = false;
  std::optional<pipeline::UserRelocalization> answer_;
  // The queue outlives the server advertised on it: a server destroyed after its queue locks the
  // queue's freed mutex (boost::lock_error when the manager unloads the nodelet).
  ros::CallbackQueue queue_;
  std::unique_ptr<ros::AsyncSpinner> spinner_;
  ros::ServiceServer server_;
};

}  // namespace stereo_fabmap_slam::ros_wiring
