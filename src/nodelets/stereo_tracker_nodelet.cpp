// StereoTracker: the tracking stage (pipeline::TrackingStage) in the nodelet graph. Stereo pairs
// in; odometry, tf odom -> base_link (and the camera's mounting), keyframes and tracked_frames
// out; the relocalize service. The stage decides; this file wires: parameters, subscriptions, a
// bounded queue and a worker thread, conversions, the relocalize_frame call to the LoopDetector,
// publishing, and in lockstep mode the wait for the other stages.
#include <chrono>
#include <condition_variable>
#include <memory>
#include <mutex>
#include <optional>
#include <thread>

#include <cv_bridge/cv_bridge.h>
#include <nav_msgs/Odometry.h>
#include <nodelet/nodelet.h>
#include <ros/callback_queue.h>
#include <ros/ros.h>
#include <std_msgs/String.h>
#include <stereo_fabmap_slam/MapLoaded.h>
#include <stereo_fabmap_slam/Relocalize.h>
#include <tf2_ros/static_transform_broadcaster.h>
#include <tf2_ros/transform_broadcaster.h>
#include <pluginlib/class_list_macros.hpp>

#include "odometry_message_builder.h"
#include "parameter_reader.h"
#include "ros_conversions.h"
#include "stage_conversions.h"
#include "stereo_fabmap_slam/odometry/frame_queue.h"
#include "stereo_fabmap_slam/pipeline/run_record.h"
#include "stereo_fabmap_slam/pipeline/tracking_stage.h"
#include "stereo_fabmap_slam/place_recognition/place_recognition_options.h"
#include "stereo_image_input.h"
#include "tracker_wiring.h"
#include "tracking_image.h"

namespace stereo_fabmap_slam {

class StereoTrackerNodelet : public nodelet::Nodelet {
 public:
  ~StereoTrackerNodelet() override {
    if (service_spinner_) service_spinner_->stop();  // before the members its callback uses
    relocalize_service_.shutdown();                  // before its queue
    pairs_.Stop();
    if (worker_.joinable()) worker_.join();
  }

 private:
  void onInit() override;
  void StartStage(const ros_input::MountedRig& rig);  // once; call with mutex_
  void Work();
  void ProcessPair(const ros_wiring::ImagePair& pair);
  void Publish(const ros::Time& stamp, const pipeline::TrackingOutput& output);
  void Relocalize(const ros::Time& stamp, const pipeline::RelocalizationRequest& request,
                  pipeline::FrameRecord* record);
  bool OnRelocalize(stereo_fabmap_slam::Relocalize::Request& request,
                    stereo_fabmap_slam::Relocalize::Response& response);

  void Log(const pipeline::InputEvent& event) { event_log_.Log(event); }

  ros_wiring::TrackerParameters parameters_;
  ros_wiring::EventLog event_log_{"stereo_tracker"};
  pipeline::SlamMode mode_ = pipeline::SlamMode::kMapping;  // under mutex_, for a late stage
  std::mutex mutex_;  // the stage: the worker, the update, mode and map callbacks share it
  std::unique_ptr<pipeline::TrackingStage> stage_;
  std::optional<ros_conversions::BaseFrameConvention> frames_;  // set with stage_
  std::optional<ros_conversions::OdometryMessageBuilder> odometry_builder_;
  std::optional<pipeline::LoadedMap> loaded_map_;  // a map loaded before the stage existed
  ros_wiring::PairQueue pairs_;
  ros_wiring::MappingProgress mapping_;  // map_graph, updates: the snapshot and lockstep's cue
  ros_wiring::UserRequests user_requests_;
  std::thread worker_;
  std::unique_ptr<ros_input::StereoImageInput> input_;
  ros::Subscriber update_subscriber_, graph_subscriber_, mode_subscriber_, loaded_subscriber_;
  ros::Publisher odometry_publisher_, keyframe_publisher_, frame_publisher_, image_publisher_,
      correction_publisher_;
  ros::ServiceClient relocalize_frame_client_;
  // The queue outlives the server advertised on it: a server destroyed after its queue locks the
  // queue's freed mutex (boost::lock_error when the manager unloads the nodelet).
  ros::CallbackQueue service_queue_;
  std::unique_ptr<ros::AsyncSpinner> service_spinner_;
  ros::ServiceServer relocalize_service_;
  std::unique_ptr<tf2_ros::TransformBroadcaster> tf_broadcaster_;
  std::unique_ptr<tf2_ros::StaticTransformBroadcaster> static_tf_broadcaster_;
  int frames_lost_with_map_kept_ = 0;       // worker only
  std::uint64_t relocalization_edges_ = 0;  // worker only: edges its relocalizations added
};

void StereoTrackerNodelet::onInit() {
  ros::NodeHandle& node = getNodeHandle();
  ros::NodeHandle& private_node = getPrivateNodeHandle();
  try {  // everything that can refuse, before any ROS object exists (a throw unloads cleanly)
    parameters_ = ros_wiring::ReadTrackerParameters(private_node);
  } catch (const std::exception& error) {
    NODELET_FATAL_STREAM("bad configuration: " << error.what());
    throw;
  }
  NODELET_INFO_STREAM("options in force:\n" << parameters_.printed);
  const ros_wiring::TrackerParameters& p = parameters_;
  pairs_.Configure(p.options.tracker.queued_pairs, p.options.tracker.catch_up_gap);
  tf_broadcaster_ = std::make_unique<tf2_ros::TransformBroadcaster>();
  static_tf_broadcaster_ = std::make_unique<tf2_ros::StaticTransformBroadcaster>();
  odometry_publisher_ = node.advertise<nav_msgs::Odometry>("odometry", 10);
  keyframe_publisher_ = node.advertise<stereo_fabmap_slam::Keyframe>("keyframes", 100);
  frame_publisher_ = node.advertise<stereo_fabmap_slam::TrackedFrame>("tracked_frames", 100);
  image_publisher_ = node.advertise<sensor_msgs::Image>("tracking_image", 2);
  update_subscriber_ = node.subscribe<stereo_fabmap_slam::KeyframeUpdate>(
      "keyframe_updates", 100, [this](const stereo_fabmap_slam::KeyframeUpdateConstPtr& message) {
        const pipeline::MappedKeyframe mapped =
            ros_conversions::FromMappedKeyframeMessage(*message);
        {
          std::lock_guard<std::mutex> lock(mutex_);
          if (stage_) stage_->ApplyUpdate(mapped.update);
        }
        mapping_.OnUpdate(mapped.keyframe_id);
      });
  if (p.loop_closing) {
    graph_subscriber_ = node.subscribe<stereo_fabmap_slam::MapGraph>(
        "map_graph", 1,
        [this](const stereo_fabmap_slam::MapGraphConstPtr& graph) { mapping_.OnGraph(*graph); });
    mode_subscriber_ = node.subscribe<std_msgs::String>(
        "mode", 1, [this](const std_msgs::StringConstPtr& message) {
          const std::optional<pipeline::SlamMode> mode = pipeline::ParseSlamMode(message->data);
          std::lock_guard<std::mutex> lock(mutex_);
          if (mode) mode_ = *mode;
          if (mode && stage_) stage_->SetMode(*mode, !mapping_.Snapshot()->empty());
        });
    loaded_subscriber_ = node.subscribe<stereo_fabmap_slam::MapLoaded>(
        "map_loaded", 1, [this](const stereo_fabmap_slam::MapLoadedConstPtr& message) {
          const pipeline::LoadedMap loaded{message->keyframes,
                                           static_cast<std::int64_t>(message->next_keyframe_id),
                                           static_cast<std::int64_t>(message->next_point_id)};
          std::lock_guard<std::mutex> lock(mutex_);
          if (stage_) stage_->OnMapLoaded(loaded);
          loaded_map_ = loaded;
        });
    correction_publisher_ =
        node.advertise<geometry_msgs::TransformStamped>("map_to_odom_correction", 10);
    relocalize_frame_client_ =
        node.serviceClient<stereo_fabmap_slam::RelocalizeFrame>("relocalize_frame", true);
    // On a queue and thread of its own: the call waits for the next frame, which the worker
    // handles meanwhile, and must not hold a thread of the manager's pool.
    ros::NodeHandle service_node(node);
    service_node.setCallbackQueue(&service_queue_);
    relocalize_service_ =
        service_node.advertiseService("relocalize", &StereoTrackerNodelet::OnRelocalize, this);
    service_spinner_ = std::make_unique<ros::AsyncSpinner>(1, &service_queue_);
    service_spinner_->start();
  }
  if (!p.use_camera_info) {
    std::lock_guard<std::mutex> lock(mutex_);
    try {
      StartStage(
          ros_input::RigFromCalibrationFile(p.calibration_file, p.rectification, p.base_to_camera));
    } catch (const std::exception& error) {
      NODELET_FATAL_STREAM("calibration: " << error.what());
      throw;
    }
  }
  input_ = std::make_unique<ros_input::StereoImageInput>(
      node, private_node, p.queue_size, p.approximate_sync,
      [this](const ros_input::StereoImageInput::Image& left,
             const ros_input::StereoImageInput::Image& right) {
        for (const pipeline::InputEvent& event : pairs_.Push(left, right)) Log(event);
      },
      [this](int side) {
        pipeline::InputMonitor* monitor = pairs_.monitor();
        if (monitor == nullptr) return;  // no calibration yet
        for (const pipeline::InputEvent& event :
             monitor->OnImage(side, ros_wiring::WallSeconds())) {
          Log(event);
        }
      });
  if (p.use_camera_info) {
    if (!p.base_to_camera) {
      NODELET_WARN(
          "use_camera_info without ~base_to_camera: camera_info does not say where the "
          "camera sits, so base_link is taken to be the raw left camera (z forward, "
          "not REP-103's x forward, z up); give ~base_to_camera for a robot's base");
    }
    input_->SubscribeCameraInfo(
        node, p.queue_size,
        [this](const sensor_msgs::CameraInfoConstPtr& left,
               const sensor_msgs::CameraInfoConstPtr& right) {
          std::lock_guard<std::mutex> lock(mutex_);
          if (stage_) return;  // the first pair defines the rectification
          try {
            StartStage(ros_input::RigFromCameraInfo(*left, *right, parameters_.base_to_camera));
          } catch (const std::exception& error) {
            NODELET_WARN_THROTTLE(5, "camera_info pair unusable: %s", error.what());
          }
        });
  }
  worker_ = std::thread(&StereoTrackerNodelet::Work, this);
  NODELET_INFO_STREAM("tracking " << input_->Describe() << (p.lockstep ? ", lockstep" : ""));
}

void StereoTrackerNodelet::StartStage(const ros_input::MountedRig& rig) {
  const ros_wiring::TrackerParameters& p = parameters_;
  pipeline::InputMonitorOptions monitor;
  monitor.max_prediction_gap = p.options.tracker.max_prediction_gap;
  monitor.unpaired_limit = p.queue_size;
  stage_ = std::make_unique<pipeline::TrackingStage>(p.options, rig.rectifier, monitor,
                                                     p.relocalizer.attempt_every_n_frames,
                                                     ros_wiring::SteadyMilliseconds);
  // odom is the base at the first frame (REP-105): the camera starts at its mounting, and every
  // pose the stages exchange is in odom.
  stage_->SetStartPose(rig.T_base_camera);
  stage_->SetMode(mode_, !mapping_.Snapshot()->empty());
  if (loaded_map_) stage_->OnMapLoaded(*loaded_map_);
  frames_.emplace(rig.T_base_camera);
  odometry_builder_.emplace(*frames_, parameters_.odom_frame, parameters_.base_frame);
  pairs_.SetMonitor(&stage_->input());
  NODELET_INFO("stereo camera: baseline %.3f m, %dx%d", stage_->camera().baseline,
               stage_->camera().size.width, stage_->camera().size.height);
  if (!p.publish_tf) return;
  geometry_msgs::TransformStamped mount;
  mount.header.stamp = ros::Time(0);  // static: valid at every time
  mount.header.frame_id = p.base_frame;
  mount.child_frame_id = p.camera_frame;
  mount.transform = ros_conversions::ToTransformMessage(frames_->T_base_camera());
  static_tf_broadcaster_->sendTransform(mount);
}

void StereoTrackerNodelet::Work() {
  std::vector<pipeline::InputEvent> events;
  while (true) {
    std::optional<ros_wiring::ImagePair> pair = pairs_.Take(&events);
    for (const pipeline::InputEvent& event : events) Log(event);
    events.clear();
    if (!pair) return;
    const double start = ros_wiring::SteadyMilliseconds();
    ProcessPair(*pair);
    pairs_.FrameDone(ros_wiring::SteadyMilliseconds() - start);
  }
}

void StereoTrackerNodelet::ProcessPair(const ros_wiring::ImagePair& pair) {
  const ros::Time stamp = pair.left->header.stamp;
  const double seconds = ros_conversions::ToSeconds(stamp);
  std::unique_lock<std::mutex> lock(mutex_);
  if (!stage_) {
    NODELET_WARN_THROTTLE(5, "no calibration yet (waiting for camera_info); frame skipped");
    return;
  }
  // Messages that cannot be images are refused before any pixel is read; colour is converted
  // to mono8, encodings cv_bridge cannot convert throw.
  std::string refusal = ros_wiring::ImageRefusal(*pair.left, *pair.right);
  cv_bridge::CvImageConstPtr left, right;
  if (refusal.empty()) {
    try {
      left = cv_bridge::toCvShare(pair.left, "mono8");
      right = cv_bridge::toCvShare(pair.right, "mono8");
    } catch (const cv_bridge::Exception& error) {
      refusal = "unsupported image encoding (" + pair.left->encoding + " / " +
                pair.right->encoding + "): " + error.what();
    }
  }
  pipeline::TrackingOutput output;
  if (!refusal.empty()) {
    Log({pipeline::InputEvent::Kind::kUnreadable, refusal + "; frame skipped", true, true});
    stage_->input().CountRefused();
  } else {
    try {
      output = stage_->Process({seconds, left->image, right->image, pair.arrival},
                               mapping_.Snapshot().get());
    } catch (const std::exception& error) {
      NODELET_WARN_THROTTLE(5, "frame skipped: %s", error.what());
    }
  }
  for (const pipeline::InputEvent& event : output.events) Log(event);
  if (!output.tracked) {
    // Said on tracked_frames too: every pair taken gets its message (lockstep waits for it).
    stereo_fabmap_slam::TrackedFrame refused = ros_conversions::RefusedFrameMessage(
        seconds, stage_->input().counts(), parameters_.odom_frame);
    refused.header.stamp = stamp;  // exactly the images' (seconds as a double round it)
    frame_publisher_.publish(refused);
    return;
  }
  Publish(stamp, output);
  pipeline::FrameRecord record = pipeline::RecordOf(output, seconds);
  if (output.relocalization) Relocalize(stamp, *output.relocalization, &record);
  if (!output.relocalization_failure.empty() && !output.user) {
    NODELET_WARN_THROTTLE(5, "relocalization: %s", output.relocalization_failure.c_str());
  }
  record.on_map = stage_->on_map();
  record.T_map_camera = stage_->T_map_camera();
  const pipeline::InputCounts counts = stage_->input().counts();
  lock.unlock();
  if (output.user) user_requests_.Answer(*output.user);
  if (parameters_.lockstep) {
    // The other stages' answers before the next pair, in the order run_dataset takes them.
    const std::int64_t keyframe = output.tracking.keyframe ? output.tracking.keyframe->id : -1;
    if (!mapping_.WaitFor(keyframe, parameters_.loop_closing, relocalization_edges_,
                          parameters_.lockstep_timeout)) {
      NODELET_WARN(
          "lockstep: no answer from the Backend or LoopDetector within %.0f s for the "
          "pair at %.3f; going on",
          parameters_.lockstep_timeout, stamp.toSec());
    }
  }
  stereo_fabmap_slam::TrackedFrame message =
      ros_conversions::ToTrackedFrameMessage(record, counts, parameters_.odom_frame);
  message.header.stamp = stamp;  // exactly the images' (seconds as a double round it)
  frame_publisher_.publish(message);
}

void StereoTrackerNodelet::Publish(const ros::Time& stamp, const pipeline::TrackingOutput& output) {
  const odometry::TrackingResult& result = output.tracking;
  if (result.state == odometry::TrackingState::kLost) {
    // A new segment once per segment, never throttled, so that they can be counted.
    if (result.keyframe && result.keyframe->starts_new_segment) {
      NODELET_WARN("tracking lost: %s", result.reason.c_str());
    } else {
      NODELET_WARN_THROTTLE(2, "tracking lost: %s", result.reason.c_str());
    }
    frames_lost_with_map_kept_ = result.map_kept ? frames_lost_with_map_kept_ + 1 : 0;
  } else if (frames_lost_with_map_kept_ > 0) {
    NODELET_INFO("tracking found the map again after %d lost frame(s); odom goes on unbroken",
                 frames_lost_with_map_kept_);
    frames_lost_with_map_kept_ = 0;
  }
  // Drawn only for someone who looks: a colour copy of every frame is not free.
  if (image_publisher_.getNumSubscribers() > 0) {
    image_publisher_.publish(ros_visualization::TrackingImageMessage(
        stage_->front_end().last_rectified_left(), result, stamp, parameters_.camera_frame));
  }
  if (result.state == odometry::TrackingState::kLost && !result.keyframe) return;  // no pose
  // A loss, or a new segment after one, is not a motion to take a twist from.
  const bool continues = result.state != odometry::TrackingState::kLost &&
                         !(result.keyframe && result.keyframe->starts_new_segment);
  // The stage tracks the camera in odom; the convention's poses are the camera's first frame's.
  const Eigen::Isometry3d T_first_camera = frames_->FromOdom(result.T_world_camera);
  const nav_msgs::Odometry odometry =
      odometry_builder_->Build(stamp, T_first_camera, result.covariance, continues);
  odometry_publisher_.publish(odometry);
  if (parameters_.publish_tf) {
    geometry_msgs::TransformStamped transform;
    transform.header = odometry.header;
    transform.child_frame_id = parameters_.base_frame;
    transform.transform = ros_conversions::ToTransformMessage(frames_->BaseInOdom(T_first_camera));
    tf_broadcaster_->sendTransform(transform);
  }
  if (result.keyframe) {
    stereo_fabmap_slam::Keyframe keyframe = ros_conversions::ToKeyframeMessage(
        *result.keyframe, stage_->camera(), parameters_.odom_frame);
    keyframe.header.stamp = stamp;
    keyframe_publisher_.publish(keyframe);
  }
}

void StereoTrackerNodelet::Relocalize(const ros::Time& stamp,
                                      const pipeline::RelocalizationRequest& request,
                                      pipeline::FrameRecord* record) {
  stereo_fabmap_slam::RelocalizeFrame call;
  call.request =
      ros_conversions::ToRelocalizeFrameRequest(request, stage_->camera(), parameters_.odom_frame);
  call.request.frame.header.stamp = stamp;
  if (!relocalize_frame_client_.isValid()) {
    relocalize_frame_client_ = getNodeHandle().serviceClient<stereo_fabmap_slam::RelocalizeFrame>(
        "relocalize_frame", true);
  }
  if (!relocalize_frame_client_.call(call)) {
    const std::string failure = "the LoopDetector's relocalize_frame service is not available";
    if (request.from_user) {
      pipeline::UserRelocalization user;
      user.message = failure;
      user_requests_.Answer(user);  // its waiting caller holds no lock of this nodelet's
    } else {
      NODELET_WARN_THROTTLE(5, "relocalization: %s", failure.c_str());
    }
    return;
  }
  const pipeline::RelocalizationAnswer answer =
      ros_conversions::FromRelocalizeFrameResponse(call.response);
  if (answer.edge) ++relocalization_edges_;
  const pipeline::RelocalizationOutcome outcome = stage_->OnRelocalization(request, answer);
  if (!answer.already_joined) {
    record->timing.relocalization_ms = answer.ms;
    record->relocalization = pipeline::DescribeRelocalization(answer.result);
    record->relocalized = answer.result.success();
  }
  if (!outcome.news.empty()) NODELET_INFO("%s", outcome.news.c_str());
  if (outcome.T_map_odom) {
    geometry_msgs::TransformStamped correction;
    correction.header.stamp = stamp;
    correction.header.frame_id = parameters_.map_frame;
    correction.child_frame_id = parameters_.odom_frame;
    correction.transform = ros_conversions::ToTransformMessage(*outcome.T_map_odom);
    correction_publisher_.publish(correction);
  }
  if (outcome.user) {
    pipeline::UserRelocalization user = *outcome.user;
    user.T_map_camera = answer.T_map_camera;
    user_requests_.Answer(user);
  }
}

bool StereoTrackerNodelet::OnRelocalize(stereo_fabmap_slam::Relocalize::Request& request,
                                        stereo_fabmap_slam::Relocalize::Response& response) {
  response.keyframe_id = -1;
  // A bounded wait: the service thread is one, and a caller waiting an hour for images that never
  // come would hold it from everyone else.
  constexpr double kLongestTimeout = 60.0;
  if (!std::isfinite(request.timeout) || request.timeout < 0 || request.timeout > kLongestTimeout) {
    response.message = "timeout must be a number of seconds in [0, 60] (0: 1 s)";
    return true;
  }
  const double timeout = request.timeout > 0 ? request.timeout : 1.0;
  if (mapping_.Snapshot()->empty()) {
    response.message = "map is empty";
    return true;
  }
  const std::optional<pipeline::UserRelocalization> answer = user_requests_.Ask(
      timeout,
      [&] {
        std::lock_guard<std::mutex> lock(mutex_);
        if (stage_) stage_->RequestRelocalization(request.reanchor);
      },
      [&] {
        std::lock_guard<std::mutex> lock(mutex_);
        if (stage_) stage_->CancelRelocalizationRequest();
      });
  if (!answer) {
    char text[96];
    std::snprintf(text, sizeof(text), "no stereo images arrived within %.1f s", timeout);
    response.message = text;
    return true;
  }
  response.success = answer->success;
  response.message = answer->message;
  response.inliers = answer->inliers;
  response.probability = answer->probability;
  response.time_ms = answer->time_ms;
  response.keyframe_id = answer->keyframe_id;
  if (response.success) {
    response.pose.header.stamp = ros::Time::now();
    response.pose.header.frame_id = parameters_.map_frame;
    // The base's pose, what a robot's navigation wants.
    response.pose.pose =
        ros_conversions::ToPoseMessage(answer->T_map_camera * frames_->T_base_camera().inverse());
  }
  return true;
}

}  // namespace stereo_fabmap_slam

PLUGINLIB_EXPORT_CLASS(stereo_fabmap_slam::StereoTrackerNodelet, nodelet::Nodelet)
