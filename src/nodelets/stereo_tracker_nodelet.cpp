// StereoTracker: synchronised raw stereo images in, odometry, tf odom -> base_link (and the
// camera's mounting, base_link -> camera) and keyframes out; the relocalize service. After a
// tracking loss it asks the LoopDetector (relocalize_frame) to find frames in the map until one is
// found, whose edge joins the new piece of odometry to the map. Everything algorithmic is
// pipeline::StereoFrontEnd and the LoopDetector's Relocalizer; this file converts, calls and
// publishes.
#include <algorithm>
#include <atomic>
#include <chrono>
#include <condition_variable>
#include <cstdint>
#include <cstring>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <thread>
#include <utility>
#include <vector>

#include <cv_bridge/cv_bridge.h>
#include <geometry_msgs/TransformStamped.h>
#include <image_transport/camera_common.h>
#include <image_transport/image_transport.h>
#include <image_transport/subscriber_filter.h>
#include <message_filters/subscriber.h>
#include <message_filters/sync_policies/approximate_time.h>
#include <message_filters/sync_policies/exact_time.h>
#include <message_filters/synchronizer.h>
#include <nav_msgs/Odometry.h>
#include <nodelet/nodelet.h>
#include <ros/callback_queue.h>
#include <ros/ros.h>
#include <sensor_msgs/CameraInfo.h>
#include <sensor_msgs/Image.h>
#include <std_msgs/String.h>
#include <stereo_fabmap_slam/MapGraph.h>
#include <stereo_fabmap_slam/MapLoaded.h>
#include <stereo_fabmap_slam/Relocalize.h>
#include <stereo_fabmap_slam/RelocalizeFrame.h>
#include <tf2_ros/static_transform_broadcaster.h>
#include <tf2_ros/transform_broadcaster.h>
#include <pluginlib/class_list_macros.hpp>

#include "base_frame_convention.h"
#include "odometry_message_builder.h"
#include "parameter_reader.h"
#include "ros_conversions.h"
#include "stereo_fabmap_slam/camera/camera_calibration.h"
#include "stereo_fabmap_slam/odometry/frame_queue.h"
#include "stereo_fabmap_slam/pipeline/stereo_front_end.h"
#include "stereo_fabmap_slam/place_recognition/place_recognition_options.h"
#include "stereo_fabmap_slam/relocalization/relocalization_options.h"
#include "tracking_image.h"

namespace stereo_fabmap_slam {

class StereoTrackerNodelet : public nodelet::Nodelet {
 public:
  ~StereoTrackerNodelet() override {
    if (service_spinner_) service_spinner_->stop();  // before the members its callback uses
    relocalize_service_.shutdown();                  // before its queue
    {
      std::lock_guard<std::mutex> lock(pair_mutex_);
      stopping_ = true;
    }
    pair_ready_.notify_all();
    if (worker_.joinable()) worker_.join();
  }

 private:
  using Image = sensor_msgs::Image;
  using ExactPolicy = message_filters::sync_policies::ExactTime<Image, Image>;
  using ApproximatePolicy = message_filters::sync_policies::ApproximateTime<Image, Image>;
  using InfoPolicy =
      message_filters::sync_policies::ExactTime<sensor_msgs::CameraInfo, sensor_msgs::CameraInfo>;

  void onInit() override;
  void LoadOptions(const ros::NodeHandle& private_node);
  // Sets the front end and, from its rectified camera's mounting, the frame conventions; once.
  // T_base_body: the rectifier's body frame in the base frame.
  void StartFrontEnd(const camera::StereoRectifier& rectifier,
                     const Eigen::Isometry3d& T_base_body);
  void OnCameraInfo(const sensor_msgs::CameraInfoConstPtr& left,
                    const sensor_msgs::CameraInfoConstPtr& right);
  // The synchroniser's callback: queues the pair for the worker, or drops it when the queue is
  // full (whole pairs only, the newest first).
  void OnImages(const sensor_msgs::ImageConstPtr& left, const sensor_msgs::ImageConstPtr& right);
  // Skips counted since the last report, taken for reporting once a second. Call with
  // pair_mutex_; warn (Warn) without it.
  struct SkipReport {
    std::uint64_t since_last = 0, in_all = 0;
    double frame_ms = 0;
  };
  SkipReport TakeSkipReport(const ros::WallTime& now);
  void Warn(const SkipReport& report);
  // The worker thread: tracks pairs one at a time.
  void Work();
  // `arrival`: the pair's place in the stream (1, 2, ...), which tells the tracker how many
  // pairs were passed over since the last one it tracked (Tracker::Track's frames_skipped).
  void ProcessPair(const sensor_msgs::ImageConstPtr& left, const sensor_msgs::ImageConstPtr& right,
                   std::uint64_t arrival);
  void OnKeyframeUpdate(const stereo_fabmap_slam::KeyframeUpdateConstPtr& update);
  // Counts images of one side (0 left, 1 right); warns when more go unpaired than the sync
  // queue can hold, and when the other camera has been silent for a second (a dropout).
  void OnSingleImage(int side);
  void Publish(const ros::Time& stamp, const odometry::TrackingResult& result);
  // After tracking: attempts a relocalization if one is due (recovery after a loss, or a user's
  // request), and answers the request. Call with mutex_.
  void RelocalizeIfDue(const ros::Time& stamp, const pipeline::FrontEndOutput& output);
  bool OnRelocalize(stereo_fabmap_slam::Relocalize::Request& request,
                    stereo_fabmap_slam::Relocalize::Response& response);

  camera::RectificationOptions rectification_options_;
  pipeline::FrontEndOptions options_;
  relocalization::RelocalizerOptions relocalizer_options_;
  std::string odom_frame_, base_frame_, camera_frame_, map_frame_;
  bool publish_tf_ = true;
  // ~base_to_camera [x y z qx qy qz qw]: the raw left camera in the base frame, replacing the
  // calibration's T_BS (and the identity camera_info implies).
  std::optional<Eigen::Isometry3d> T_base_left_raw_;
  std::optional<ros_conversions::BaseFrameConvention> frames_;  // set with front_end_
  std::optional<ros_conversions::OdometryMessageBuilder> odometry_builder_;
  std::mutex mutex_;  // image and update callbacks may run on different manager threads
  std::unique_ptr<pipeline::StereoFrontEnd> front_end_;
  ros::Time last_stamp_;
  int queue_size_ = 10;
  std::atomic<std::uint64_t> left_images_{0}, right_images_{0}, pairs_{0};
  // Wall time [s] of each side's latest image, for telling a camera that dropped out.
  std::atomic<double> last_arrival_[2] = {0.0, 0.0};
  std::atomic<bool> dropout_reported_{false};
  // The last tracked pair's images (shared with their messages), for telling a frozen camera:
  // the same image again under a new stamp. Worker thread only.
  cv_bridge::CvImageConstPtr previous_left_, previous_right_;
  int frozen_frames_ = 0;
  int frames_lost_with_map_kept_ = 0;       // lost in a row, the tracker's map kept
  std::uint64_t last_tracked_arrival_ = 0;  // ImagePair::arrival of the last pair tracked

  // Between the synchroniser and the worker: a bounded queue (tracker/queued_pairs), so that a
  // tracker slower than the camera (a bag played fast, a busy machine) skips pairs instead of
  // falling ever further behind, and the subscribers' queues never overflow (which would drop a
  // left image without its right). The worker takes pairs so that the gaps between tracked
  // pairs stay short (odometry::FrameQueue). Skipped pairs, dropped from a full queue or passed
  // over, are counted and reported once a second.
  struct ImagePair {
    sensor_msgs::ImageConstPtr left, right;
    std::uint64_t arrival = 0;  // its place in the stream of pairs (pairs_ when it came)
  };
  std::mutex pair_mutex_;
  std::condition_variable pair_ready_;
  std::optional<odometry::FrameQueue<ImagePair>> waiting_pairs_;  // set in onInit
  bool stopping_ = false;
  std::uint64_t skipped_pairs_ = 0, skipped_reported_ = 0;
  ros::WallTime last_skip_report_;
  double last_frame_ms_ = 0;  // the last pair's tracking time, for the report
  std::thread worker_;

  // Images through image_transport: ~image_transport (raw by default) picks the transport, so a
  // compressed stream works where its plugin is installed.
  std::unique_ptr<image_transport::ImageTransport> image_transport_;
  image_transport::SubscriberFilter left_subscriber_, right_subscriber_;
  message_filters::Subscriber<sensor_msgs::CameraInfo> left_info_subscriber_,
      right_info_subscriber_;
  std::unique_ptr<message_filters::Synchronizer<ExactPolicy>> exact_sync_;
  std::unique_ptr<message_filters::Synchronizer<ApproximatePolicy>> approximate_sync_;
  std::unique_ptr<message_filters::Synchronizer<InfoPolicy>> info_sync_;
  ros::Subscriber update_subscriber_, graph_subscriber_;
  ros::Publisher odometry_publisher_, keyframe_publisher_, tracking_image_publisher_;
  ros::ServiceClient relocalize_frame_client_;
  // The queue outlives the server advertised on it: a server destroyed after its queue locks
  // the queue's freed mutex (the manager aborted with boost::lock_error in about a third of the
  // unloads at the end of a launch).
  ros::CallbackQueue service_queue_;
  std::unique_ptr<ros::AsyncSpinner> service_spinner_;
  ros::ServiceServer relocalize_service_;

  // Recovery (mapping): set by a loss while there is a map, cleared when a frame is found in it.
  // Localization: relocalized until found, then at every keyframe; each success gives map ->
  // odom (map_to_odom_correction, which the Backend broadcasts).
  std::atomic<bool> map_has_keyframes_{false};  // from map_graph
  std::atomic<bool> localization_{false};       // from the LoopDetector's mode
  bool recovering_ = false;
  bool localized_ = false;
  int frames_since_attempt_ = 0;
  std::int64_t next_keyframe_id_ = 0, next_point_id_ = 0;  // a loaded map's, for a late front end
  ros::Subscriber mode_subscriber_, map_loaded_subscriber_;
  ros::Publisher correction_publisher_;

  // A user's relocalize request, answered by the next frame's image callback.
  struct Request {
    std::uint64_t id = 0;  // answers are matched to the request they were taken for
    bool pending = false, answered = false, reanchor = false;
    stereo_fabmap_slam::RelocalizeFrame::Response result;
    ros::Time stamp;
    std::string failure;  // set if the frame could not be relocalized at all
  };
  std::mutex request_mutex_;
  std::condition_variable request_answered_;
  Request request_;
  std::uint64_t next_request_id_ = 1;
  std::unique_ptr<tf2_ros::TransformBroadcaster> tf_broadcaster_;
  std::unique_ptr<tf2_ros::StaticTransformBroadcaster> static_tf_broadcaster_;
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
  relocalizer_options_ = ros_parameters::ReadModuleOptions(private_node, relocalizer_options_);
  printed += ros_parameters::PrintedOptions(relocalizer_options_);
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
  waiting_pairs_.emplace(static_cast<std::size_t>(options_.tracker.queued_pairs),
                         options_.tracker.catch_up_gap);
  // REP-105 names, as rtabmap_ros and slam_toolbox default to.
  odom_frame_ = private_node.param<std::string>("odom_frame", "odom");
  base_frame_ = private_node.param<std::string>("base_frame", "base_link");
  camera_frame_ = private_node.param<std::string>("camera_frame", "camera_optical");
  map_frame_ = private_node.param<std::string>("map_frame", "map");
  publish_tf_ = private_node.param("publish_tf", true);
  std::vector<double> mount;
  if (private_node.getParam("base_to_camera", mount)) {
    if (mount.size() != 7) {
      NODELET_FATAL("~base_to_camera needs 7 numbers [x, y, z, qx, qy, qz, qw], got %zu",
                    mount.size());
      throw std::runtime_error("bad ~base_to_camera");
    }
    const Eigen::Quaterniond rotation(mount[6], mount[3], mount[4], mount[5]);
    if (rotation.norm() < 1e-6) {
      NODELET_FATAL("~base_to_camera: the quaternion has zero length");
      throw std::runtime_error("bad ~base_to_camera");
    }
    Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
    T.linear() = rotation.normalized().toRotationMatrix();
    T.translation() = Eigen::Vector3d(mount[0], mount[1], mount[2]);
    T_base_left_raw_ = T;
  }
  tf_broadcaster_ = std::make_unique<tf2_ros::TransformBroadcaster>();
  static_tf_broadcaster_ = std::make_unique<tf2_ros::StaticTransformBroadcaster>();
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
      camera::StereoCalibration calibration = camera::ReadStereoCalibrationYaml(calibration_file);
      if (T_base_left_raw_) {
        // Move both cameras so that the left one sits at the given mounting; the stereo
        // extrinsic between them stays.
        const Eigen::Isometry3d move = *T_base_left_raw_ * calibration.left.T_body_camera.inverse();
        calibration.left.T_body_camera = move * calibration.left.T_body_camera;
        calibration.right.T_body_camera = move * calibration.right.T_body_camera;
      }
      // The calibration's body is the base unless it says where the base is (T_body_base);
      // ~base_to_camera places the camera on the base directly.
      StartFrontEnd(
          camera::StereoRectifier::FromCalibration(calibration, rectification_options_),
          T_base_left_raw_ ? Eigen::Isometry3d::Identity() : calibration.T_body_base.inverse());
    } catch (const std::exception& error) {
      NODELET_FATAL_STREAM("calibration: " << error.what());
      throw;
    }
  } else {
    // Camera info follows its image topic (as image_transport's CameraSubscriber does): one
    // remap of left/image_raw moves both.
    left_info_subscriber_.subscribe(
        node, image_transport::getCameraInfoTopic(node.resolveName("left/image_raw")), queue_size);
    right_info_subscriber_.subscribe(
        node, image_transport::getCameraInfoTopic(node.resolveName("right/image_raw")), queue_size);
    NODELET_INFO_STREAM("calibration from " << left_info_subscriber_.getTopic() << " + "
                                            << right_info_subscriber_.getTopic());
    info_sync_ = std::make_unique<message_filters::Synchronizer<InfoPolicy>>(
        InfoPolicy(queue_size), left_info_subscriber_, right_info_subscriber_);
    info_sync_->registerCallback(&StereoTrackerNodelet::OnCameraInfo, this);
  }

  odometry_publisher_ = node.advertise<nav_msgs::Odometry>("odometry", 10);
  keyframe_publisher_ = node.advertise<stereo_fabmap_slam::Keyframe>("keyframes", 100);
  tracking_image_publisher_ = node.advertise<sensor_msgs::Image>("tracking_image", 2);
  update_subscriber_ =
      node.subscribe("keyframe_updates", 100, &StereoTrackerNodelet::OnKeyframeUpdate, this);
  if (options_.place_features) {
    relocalize_frame_client_ =
        node.serviceClient<stereo_fabmap_slam::RelocalizeFrame>("relocalize_frame", true);
    graph_subscriber_ = node.subscribe<stereo_fabmap_slam::MapGraph>(
        "map_graph", 1, [this](const stereo_fabmap_slam::MapGraphConstPtr& graph) {
          map_has_keyframes_ = !graph->keyframe_ids.empty();
        });
    mode_subscriber_ =
        node.subscribe<std_msgs::String>("mode", 1, [this](const std_msgs::StringConstPtr& mode) {
          std::lock_guard<std::mutex> lock(mutex_);
          const bool localization = mode->data == "localization";
          // Back to mapping: the odometry goes on in a new piece (the Backend and LoopDetector
          // start one), which a relocalization joins to the map.
          if (localization_ && !localization) recovering_ = map_has_keyframes_.load();
          localization_ = localization;
          localized_ = false;
          frames_since_attempt_ = 0;
        });
    map_loaded_subscriber_ = node.subscribe<stereo_fabmap_slam::MapLoaded>(
        "map_loaded", 1, [this](const stereo_fabmap_slam::MapLoadedConstPtr& loaded) {
          std::lock_guard<std::mutex> lock(mutex_);
          // A new piece of odometry, continuous in odom, numbered above the map (the keyframes
          // so far have ids the map may use too); it is not in the loaded map until a
          // relocalization finds it there.
          if (front_end_) {
            front_end_->StartNewMap();
            front_end_->SkipIdsBelow(static_cast<std::int64_t>(loaded->next_keyframe_id),
                                     static_cast<std::int64_t>(loaded->next_point_id));
          }
          next_keyframe_id_ = static_cast<std::int64_t>(loaded->next_keyframe_id);
          next_point_id_ = static_cast<std::int64_t>(loaded->next_point_id);
          map_has_keyframes_ = loaded->keyframes > 0;
          recovering_ = !localization_;
          localized_ = false;
          frames_since_attempt_ = 0;
        });
    correction_publisher_ =
        node.advertise<geometry_msgs::TransformStamped>("map_to_odom_correction", 10);
    // On a queue and thread of its own: the call waits for the next frame, which the image
    // callback handles meanwhile, and must not hold a thread of the manager's pool.
    ros::NodeHandle service_node(node);
    service_node.setCallbackQueue(&service_queue_);
    relocalize_service_ =
        service_node.advertiseService("relocalize", &StereoTrackerNodelet::OnRelocalize, this);
    service_spinner_ = std::make_unique<ros::AsyncSpinner>(1, &service_queue_);
    service_spinner_->start();
  }

  image_transport_ = std::make_unique<image_transport::ImageTransport>(node);
  const image_transport::TransportHints hints("raw", ros::TransportHints(), private_node);
  left_subscriber_.subscribe(*image_transport_, "left/image_raw", queue_size, hints);
  right_subscriber_.subscribe(*image_transport_, "right/image_raw", queue_size, hints);
  left_subscriber_.registerCallback(
      [this](const sensor_msgs::ImageConstPtr&) { OnSingleImage(0); });
  right_subscriber_.registerCallback(
      [this](const sensor_msgs::ImageConstPtr&) { OnSingleImage(1); });
  if (approximate) {
    approximate_sync_ = std::make_unique<message_filters::Synchronizer<ApproximatePolicy>>(
        ApproximatePolicy(queue_size), left_subscriber_, right_subscriber_);
    approximate_sync_->registerCallback(&StereoTrackerNodelet::OnImages, this);
  } else {
    exact_sync_ = std::make_unique<message_filters::Synchronizer<ExactPolicy>>(
        ExactPolicy(queue_size), left_subscriber_, right_subscriber_);
    exact_sync_->registerCallback(&StereoTrackerNodelet::OnImages, this);
  }
  worker_ = std::thread(&StereoTrackerNodelet::Work, this);
  NODELET_INFO_STREAM("tracking " << left_subscriber_.getTopic() << " + "
                                  << right_subscriber_.getTopic()
                                  << (approximate ? " (approximate" : " (exact") << " time sync)");
}

void StereoTrackerNodelet::OnCameraInfo(const sensor_msgs::CameraInfoConstPtr& left,
                                        const sensor_msgs::CameraInfoConstPtr& right) {
  std::lock_guard<std::mutex> lock(mutex_);
  if (front_end_) return;  // the first pair defines the rectification
  try {
    StartFrontEnd(ros_conversions::RectifierFromCameraInfo(
                      *left, *right, T_base_left_raw_.value_or(Eigen::Isometry3d::Identity())),
                  Eigen::Isometry3d::Identity());
    front_end_->SkipIdsBelow(next_keyframe_id_, next_point_id_);
    NODELET_INFO("stereo model from camera_info: baseline %.3f m", front_end_->camera().baseline);
  } catch (const std::exception& error) {
    NODELET_WARN_THROTTLE(5, "camera_info pair unusable: %s", error.what());
  }
}

void StereoTrackerNodelet::StartFrontEnd(const camera::StereoRectifier& rectifier,
                                         const Eigen::Isometry3d& T_base_body) {
  front_end_ = std::make_unique<pipeline::StereoFrontEnd>(options_, rectifier, SteadyMilliseconds);
  frames_.emplace(T_base_body * rectifier.T_body_rectified_left());
  odometry_builder_.emplace(*frames_, odom_frame_, base_frame_);
  if (publish_tf_) {
    geometry_msgs::TransformStamped mount;
    mount.header.stamp = ros::Time(0);  // static: valid at every time
    mount.header.frame_id = base_frame_;
    mount.child_frame_id = camera_frame_;
    mount.transform = ros_conversions::ToTransformMessage(frames_->T_base_camera());
    static_tf_broadcaster_->sendTransform(mount);
  }
}

void StereoTrackerNodelet::OnSingleImage(int side) {
  const char* names[2] = {"left", "right"};
  const double now = ros::WallTime::now().toSec();
  if (last_arrival_[1 - side].load() == 0.0) last_arrival_[1 - side] = now;  // first image
  last_arrival_[side] = now;
  // A second without the other side while this one streams (20 frames at 20 Hz): not a stamp
  // mismatch but a camera that stopped.
  const double silent = now - last_arrival_[1 - side].load();
  if (silent > 1.0) {
    dropout_reported_ = true;
    NODELET_WARN_THROTTLE(2,
                          "no %s images for %.1f s while %s images arrive: a camera dropped "
                          "out; no stereo pairs, tracking waits for it",
                          names[1 - side], silent, names[side]);
    return;
  }
  std::atomic<std::uint64_t>& count = side == 0 ? left_images_ : right_images_;
  const std::uint64_t unpaired = ++count - pairs_.load();
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
  const std::uint64_t arrival = ++pairs_;
  if (dropout_reported_.exchange(false)) NODELET_INFO("stereo pairs arrive again");
  SkipReport report;
  {
    std::lock_guard<std::mutex> lock(pair_mutex_);
    // A full queue drops the newest pair: what waits stays a contiguous stretch of the stream.
    if (!waiting_pairs_->Push(left_message->header.stamp.toSec(),
                              ImagePair{left_message, right_message, arrival})) {
      ++skipped_pairs_;
    }
    report = TakeSkipReport(ros::WallTime::now());
  }
  pair_ready_.notify_one();
  Warn(report);
}

StereoTrackerNodelet::SkipReport StereoTrackerNodelet::TakeSkipReport(const ros::WallTime& now) {
  SkipReport report;
  if (skipped_pairs_ > skipped_reported_ && (now - last_skip_report_).toSec() >= 1.0) {
    report.since_last = skipped_pairs_ - skipped_reported_;
    report.in_all = skipped_pairs_;
    report.frame_ms = last_frame_ms_;
    skipped_reported_ = skipped_pairs_;
    last_skip_report_ = now;
  }
  return report;
}

void StereoTrackerNodelet::Warn(const SkipReport& report) {
  if (report.since_last == 0) return;
  NODELET_WARN(
      "skipped %lu stereo pair(s) in the last second: the tracker was still busy "
      "(%.0f ms for its last pair); %lu skipped in all",
      static_cast<unsigned long>(report.since_last), report.frame_ms,
      static_cast<unsigned long>(report.in_all));
}

void StereoTrackerNodelet::Work() {
  while (true) {
    ImagePair pair;
    SkipReport report;
    {
      std::unique_lock<std::mutex> lock(pair_mutex_);
      // Idle with skips not yet reported (the stream ended or paused): report them when their
      // second is up rather than never.
      while (!stopping_ && waiting_pairs_->empty()) {
        if (skipped_pairs_ == skipped_reported_) {
          pair_ready_.wait(lock);
          continue;
        }
        const double wait = 1.0 - (ros::WallTime::now() - last_skip_report_).toSec();
        if (wait > 0) pair_ready_.wait_for(lock, std::chrono::duration<double>(wait));
        report = TakeSkipReport(ros::WallTime::now());
        if (report.since_last > 0) break;
      }
      if (stopping_) return;
      if (!waiting_pairs_->empty()) {
        odometry::FrameQueue<ImagePair>::Taken taken = waiting_pairs_->Take();
        skipped_pairs_ += taken.skipped;
        pair = std::move(taken.frame);
      }
    }
    Warn(report);
    if (!pair.left) continue;
    const double start = SteadyMilliseconds();
    ProcessPair(pair.left, pair.right, pair.arrival);
    std::lock_guard<std::mutex> lock(pair_mutex_);
    last_frame_ms_ = SteadyMilliseconds() - start;
  }
}

void StereoTrackerNodelet::ProcessPair(const sensor_msgs::ImageConstPtr& left_message,
                                       const sensor_msgs::ImageConstPtr& right_message,
                                       std::uint64_t arrival) {
  std::lock_guard<std::mutex> lock(mutex_);
  if (!front_end_) {
    NODELET_WARN_THROTTLE(5, "no calibration yet (waiting for camera_info); frame skipped");
    return;
  }
  for (const sensor_msgs::ImageConstPtr& image : {left_message, right_message}) {
    const std::string problem = ros_conversions::MalformedImageReason(*image);
    if (!problem.empty()) {
      NODELET_WARN_THROTTLE(5, "malformed image on %s: %s; frame skipped",
                            image == left_message ? "left/image_raw" : "right/image_raw",
                            problem.c_str());
      return;
    }
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
  // A camera that freezes sends its last image again under new stamps: tracking it would
  // claim the robot stands still. Skipped, and said so, until the image changes.
  const auto same_image = [](const cv_bridge::CvImageConstPtr& a,
                             const cv_bridge::CvImageConstPtr& b) {
    return a && b && a->image.size() == b->image.size() && a->image.isContinuous() &&
           b->image.isContinuous() &&
           std::memcmp(a->image.data, b->image.data, a->image.total() * a->image.elemSize()) == 0;
  };
  const bool left_frozen = same_image(left, previous_left_);
  const bool right_frozen = same_image(right, previous_right_);
  if (stamp > last_stamp_ && (left_frozen || right_frozen)) {
    ++frozen_frames_;
    NODELET_WARN_THROTTLE(2,
                          "the %s frozen: the same image %d time(s) in a row under new stamps; "
                          "frames skipped until it changes",
                          left_frozen && right_frozen ? "left and right cameras are"
                          : left_frozen               ? "left camera is"
                                                      : "right camera is",
                          frozen_frames_);
    return;
  }
  if (frozen_frames_ > 0) {
    NODELET_INFO("the camera images change again after %d frozen frame(s)", frozen_frames_);
    frozen_frames_ = 0;
  }
  previous_left_ = left;
  previous_right_ = right;
  if (!last_stamp_.isZero() && stamp <= last_stamp_) {
    NODELET_WARN("time went backwards (%.3f after %.3f; a looped bag?): tracking reset",
                 stamp.toSec(), last_stamp_.toSec());
    front_end_->Reset();
  } else if (!last_stamp_.isZero() &&
             (stamp - last_stamp_).toSec() > options_.tracker.max_prediction_gap) {
    NODELET_WARN(
        "no stereo pairs for %.1f s (a gap in the images): the motion model assumes no "
        "motion across it; a lost track relocalizes",
        (stamp - last_stamp_).toSec());
  }
  last_stamp_ = stamp;
  // Pairs between this one and the last tracked: passed over in the queue, dropped from a full
  // one, or taken and refused above. Capped, as beyond a few the look-ahead reaches a whole gap.
  constexpr std::uint64_t kMostSkippedToCount = 100;
  const int skipped_before =
      static_cast<int>(last_tracked_arrival_ == 0 || arrival <= last_tracked_arrival_
                           ? 0
                           : std::min(arrival - last_tracked_arrival_ - 1, kMostSkippedToCount));
  last_tracked_arrival_ = arrival;
  try {
    const pipeline::FrontEndOutput output =
        front_end_->Process(stamp.toSec(), left->image, right->image, skipped_before);
    if (output.tracking.state == odometry::TrackingState::kLost) {
      if (output.tracking.keyframe && output.tracking.keyframe->starts_new_map) {
        // A new piece of odometry: once per piece, never throttled, so that they can be counted.
        NODELET_WARN("tracking lost: %s", output.tracking.reason.c_str());
      } else {
        NODELET_WARN_THROTTLE(2, "tracking lost: %s", output.tracking.reason.c_str());
      }
      // Counted while the map is kept; a new piece ends the count (its warning said so).
      frames_lost_with_map_kept_ = output.tracking.map_kept ? frames_lost_with_map_kept_ + 1 : 0;
    } else if (frames_lost_with_map_kept_ > 0) {
      NODELET_INFO("tracking found the map again after %d lost frame(s); odom goes on unbroken",
                   frames_lost_with_map_kept_);
      frames_lost_with_map_kept_ = 0;
    }
    Publish(stamp, output.tracking);
    // Drawn only for someone who looks: a colour copy of every frame is not free.
    if (tracking_image_publisher_.getNumSubscribers() > 0) {
      tracking_image_publisher_.publish(ros_visualization::TrackingImageMessage(
          front_end_->last_rectified_left(), output.tracking, stamp, camera_frame_));
    }
    if (options_.place_features) RelocalizeIfDue(stamp, output);
  } catch (const std::exception& error) {
    NODELET_WARN_THROTTLE(5, "frame skipped: %s", error.what());
  }
}

void StereoTrackerNodelet::Publish(const ros::Time& stamp, const odometry::TrackingResult& result) {
  if (result.state == odometry::TrackingState::kLost && !result.keyframe)
    return;  // no pose to give
  // A loss, or a new piece of odometry after one, is not a motion to take a twist from.
  const bool continues = result.state != odometry::TrackingState::kLost &&
                         !(result.keyframe && result.keyframe->starts_new_map);
  const nav_msgs::Odometry odometry =
      odometry_builder_->Build(stamp, result.T_world_camera, result.covariance, continues);
  odometry_publisher_.publish(odometry);

  if (publish_tf_) {
    geometry_msgs::TransformStamped transform;
    transform.header = odometry.header;
    transform.child_frame_id = base_frame_;
    transform.transform =
        ros_conversions::ToTransformMessage(frames_->BaseInOdom(result.T_world_camera));
    tf_broadcaster_->sendTransform(transform);
  }

  if (result.keyframe) {
    keyframe_publisher_.publish(ros_conversions::ToKeyframeMessage(
        frames_->KeyframeToOdom(*result.keyframe), front_end_->camera(), odom_frame_));
  }
}

void StereoTrackerNodelet::RelocalizeIfDue(const ros::Time& stamp,
                                           const pipeline::FrontEndOutput& output) {
  const odometry::TrackingResult& result = output.tracking;
  const bool localization = localization_;
  // A new piece of odometry (after a loss, or a reset when time went backwards) is not in the
  // map until a relocalization (or a loop) joins it.
  const bool new_piece = result.keyframe && result.keyframe->starts_new_map;
  // A lost frame whose map the tracker kept has no pose, but the odometry goes on unbroken if
  // a later frame is tracked; if none is, a new piece follows.
  const bool broken =
      new_piece || (result.state == odometry::TrackingState::kLost && !result.map_kept);
  if (localization) {
    if (broken) localized_ = false;  // the old map -> odom no longer holds
  } else if (broken && map_has_keyframes_) {
    if (!recovering_) frames_since_attempt_ = 0;
    recovering_ = true;
  }
  bool user_request;
  std::uint64_t request_id = 0;
  {
    std::lock_guard<std::mutex> lock(request_mutex_);
    user_request = request_.pending && !request_.answered;
    request_id = request_.id;
  }
  const int every = relocalizer_options_.attempt_every_n_frames;
  bool due;
  if (localization) {
    due = map_has_keyframes_ &&
          (localized_ ? result.keyframe.has_value() : frames_since_attempt_++ % every == 0);
  } else {
    due = recovering_ && frames_since_attempt_++ % every == 0;
  }
  if (!user_request && !due) return;

  stereo_fabmap_slam::RelocalizeFrame call;
  std::string failure;
  if (result.state == odometry::TrackingState::kLost && !result.keyframe) {
    // No pose of its own (only the motion model's prediction): nothing to relocalize from.
    failure =
        result.map_kept
            ? "this frame could not be tracked (the tracker searches the next ones in its map)"
            : "tracking is lost and the frame has too few stereo points";
  } else {
    map::Keyframe frame;
    frame.timestamp = stamp.toSec();
    frame.T_world_camera = frames_->ToOdom(result.T_world_camera);
    frame.features = output.features;
    frame.map_point_ids.assign(frame.features.size(), -1);
    frame.place_descriptors =
        result.keyframe ? result.keyframe->place_descriptors : front_end_->DescribeLastFrame();
    call.request.frame =
        ros_conversions::ToKeyframeMessage(frame, front_end_->camera(), odom_frame_);
    call.request.frame.header.stamp = stamp;
    const bool recover = !localization && recovering_;
    call.request.mode = recover ? stereo_fabmap_slam::RelocalizeFrame::Request::RECOVER
                                : stereo_fabmap_slam::RelocalizeFrame::Request::ANYWHERE;
    call.request.reference_keyframe_id = result.reference_keyframe;
    call.request.T_reference_camera = ros_conversions::ToPoseMessage(result.T_keyframe_camera);
    bool reanchor;
    {
      std::lock_guard<std::mutex> lock(request_mutex_);
      reanchor = user_request && request_.reanchor;
    }
    // Mapping: after a loss the edge is what joins the odometry to the map; while tracking is
    // fine it corrects map -> odom only when the user asks to re-anchor. Localization never
    // changes the map: the result moves map -> odom instead.
    call.request.add_edge = !localization && (recover || reanchor);
    if (!relocalize_frame_client_.isValid()) {
      relocalize_frame_client_ = getNodeHandle().serviceClient<stereo_fabmap_slam::RelocalizeFrame>(
          "relocalize_frame", true);
    }
    if (!relocalize_frame_client_.call(call)) {
      failure = "the LoopDetector's relocalize_frame service is not available";
    } else if (localization) {
      if (call.response.success && call.response.map_pose_known) {
        const Eigen::Isometry3d T_map_odom =
            ros_conversions::FromPoseMessage(call.response.T_map_camera) *
            frames_->ToOdom(result.T_world_camera).inverse();
        geometry_msgs::TransformStamped correction;
        correction.header.stamp = stamp;
        correction.header.frame_id = map_frame_;
        correction.child_frame_id = odom_frame_;
        correction.transform = ros_conversions::ToTransformMessage(T_map_odom);
        correction_publisher_.publish(correction);
        if (!localized_) {
          NODELET_INFO("localized in the map against keyframe %lu (%d inliers)",
                       static_cast<unsigned long>(call.response.keyframe_id),
                       call.response.inliers);
        }
        localized_ = true;
        frames_since_attempt_ = 0;
      }
    } else if (recovering_ && (call.response.success || call.response.already_joined)) {
      recovering_ = false;
      if (call.response.success) {
        NODELET_INFO("relocalized after tracking loss against keyframe %lu (%d inliers)",
                     static_cast<unsigned long>(call.response.keyframe_id), call.response.inliers);
      }
    }
  }
  if (!failure.empty() && !user_request) {
    NODELET_WARN_THROTTLE(5, "relocalization: %s", failure.c_str());
  }
  if (user_request) {
    std::lock_guard<std::mutex> lock(request_mutex_);
    if (request_.id != request_id || !request_.pending) return;  // its caller gave up
    request_.answered = true;
    request_.result = call.response;
    request_.stamp = stamp;
    request_.failure = failure;
    request_answered_.notify_all();
  }
}

bool StereoTrackerNodelet::OnRelocalize(stereo_fabmap_slam::Relocalize::Request& request,
                                        stereo_fabmap_slam::Relocalize::Response& response) {
  response.keyframe_id = -1;
  if (!map_has_keyframes_) {
    response.message = "map is empty";
    return true;
  }
  const double timeout = request.timeout > 0 ? request.timeout : 1.0;
  std::unique_lock<std::mutex> lock(request_mutex_);
  if (request_.pending) {
    response.message = "another relocalize call is waiting for a frame";
    return true;
  }
  request_ = Request();
  request_.id = next_request_id_++;
  request_.pending = true;
  request_.reanchor = request.reanchor;
  const bool answered = request_answered_.wait_for(lock, std::chrono::duration<double>(timeout),
                                                   [&] { return request_.answered; });
  request_.pending = false;
  if (!answered) {
    char text[96];
    std::snprintf(text, sizeof(text), "no stereo images arrived within %.1f s", timeout);
    response.message = text;
    return true;
  }
  if (!request_.failure.empty()) {
    response.message = request_.failure;
    return true;
  }
  const stereo_fabmap_slam::RelocalizeFrame::Response& result = request_.result;
  response.success = result.success && result.map_pose_known;
  response.message = result.success && !result.map_pose_known
                         ? "found against keyframe " + std::to_string(result.keyframe_id) +
                               ", which the map graph does not hold yet"
                         : result.status + ": " + result.message;
  response.inliers = result.inliers;
  response.probability = result.probability;
  response.time_ms = result.time_ms;
  if (result.success) response.keyframe_id = static_cast<std::int64_t>(result.keyframe_id);
  if (response.success) {
    response.pose.header.stamp = request_.stamp;
    response.pose.header.frame_id = map_frame_;
    // The base's pose, what a robot's navigation wants. frames_ was set before the frame that
    // answered was tracked, and that answer was handed over under request_mutex_.
    response.pose.pose = ros_conversions::ToPoseMessage(
        ros_conversions::FromPoseMessage(result.T_map_camera) * frames_->T_base_camera().inverse());
  }
  return true;
}

void StereoTrackerNodelet::OnKeyframeUpdate(
    const stereo_fabmap_slam::KeyframeUpdateConstPtr& message) {
  std::lock_guard<std::mutex> lock(mutex_);
  if (!front_end_) return;
  try {
    front_end_->ApplyUpdate(
        frames_->UpdateFromOdom(ros_conversions::FromKeyframeUpdateMessage(*message)));
  } catch (const std::exception& error) {
    NODELET_WARN_THROTTLE(5, "keyframe update ignored: %s", error.what());
  }
}

}  // namespace stereo_fabmap_slam

PLUGINLIB_EXPORT_CLASS(stereo_fabmap_slam::StereoTrackerNodelet, nodelet::Nodelet)
