// Backend: the mapping stage (pipeline::MappingStage) in the nodelet graph. Keyframes, the
// LoopDetector's place results and relocalization edges, loaded maps, the mode and localization's
// map -> odom in; keyframe_updates (one per keyframe), map_graph and tf map -> odom out. The
// stage decides; this file queues every input in arrival order for a worker thread it owns,
// converts, calls and publishes.
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <thread>
#include <vector>

#include <geometry_msgs/TransformStamped.h>
#include <nodelet/nodelet.h>
#include <ros/ros.h>
#include <std_msgs/Header.h>
#include <std_msgs/String.h>
#include <stereo_fabmap_slam/MapLoaded.h>
#include <tf2_ros/transform_broadcaster.h>
#include <pluginlib/class_list_macros.hpp>

#include "backend_wiring.h"
#include "parameter_reader.h"
#include "ros_conversions.h"
#include "stage_conversions.h"
#include "stereo_fabmap_slam/pipeline/mapping_stage.h"
#include "tracker_wiring.h"
#include "transform_repeater.h"

namespace stereo_fabmap_slam {

class BackendNodelet : public nodelet::Nodelet {
 public:
  ~BackendNodelet() override {
    inputs_.Stop();
    if (worker_.joinable()) worker_.join();
  }

 private:
  void onInit() override;
  void Push(ros_wiring::BackendInput input) { inputs_.Push(std::move(input)); }
  void Work();
  void OnTfTimer(const ros::WallTimerEvent&);

  std::string map_frame_, odom_frame_;
  std::optional<pipeline::MappingStage> stage_;  // the worker's only
  ros::Subscriber keyframe_subscriber_, place_subscriber_, edge_subscriber_, loaded_subscriber_,
      mode_subscriber_, correction_subscriber_;
  ros::Publisher update_publisher_, graph_publisher_;
  std::unique_ptr<tf2_ros::TransformBroadcaster> tf_broadcaster_;
  ros::WallTimer tf_timer_;
  ros::Time last_tf_stamp_;                 // only the timer's thread touches it
  ros_wiring::TransformRepeater repeater_;  // map -> odom while the clock stands still
  ros_wiring::BackendQueue inputs_;         // in the order they arrived: the stage takes them so
  std::thread worker_;
  std::mutex map_to_odom_mutex_;
  Eigen::Isometry3d map_to_odom_ = Eigen::Isometry3d::Identity();
};

void BackendNodelet::onInit() {
  ros::NodeHandle& private_node = getPrivateNodeHandle();
  backend::BundleAdjustmentOptions options;
  backend::PoseGraphOptions pose_graph_options;
  backend::GlobalRefinementOptions refinement_options;
  try {  // before any ROS object exists: a throw unloads cleanly
    options = ros_parameters::ReadModuleOptions(private_node, options);
    pose_graph_options = ros_parameters::ReadModuleOptions(private_node, pose_graph_options);
    refinement_options = ros_parameters::ReadModuleOptions(private_node, refinement_options);
    ros_parameters::RejectUnknownParameters(
        private_node, {"config_file", "map_frame", "odom_frame", "publish_tf", "tf_rate"});
  } catch (const std::exception& error) {
    NODELET_FATAL_STREAM("bad configuration: " << error.what());
    throw;
  }
  NODELET_INFO_STREAM("options in force:\n"
                      << ros_parameters::PrintedOptions(options)
                      << ros_parameters::PrintedOptions(pose_graph_options)
                      << ros_parameters::PrintedOptions(refinement_options));
  stage_.emplace(options, pose_graph_options, ros_wiring::SteadyMilliseconds);
  stage_->SetGlobalRefinement(refinement_options);
  map_frame_ = private_node.param<std::string>("map_frame", "map");
  odom_frame_ = private_node.param<std::string>("odom_frame", "odom");
  const double tf_rate = private_node.param("tf_rate", 20.0);
  ros::NodeHandle& node = getNodeHandle();
  update_publisher_ = node.advertise<stereo_fabmap_slam::KeyframeUpdate>("keyframe_updates", 100);
  graph_publisher_ = node.advertise<stereo_fabmap_slam::MapGraph>("map_graph", 1, true);
  tf_broadcaster_ = std::make_unique<tf2_ros::TransformBroadcaster>();
  worker_ = std::thread(&BackendNodelet::Work, this);
  keyframe_subscriber_ = node.subscribe<stereo_fabmap_slam::Keyframe>(
      "keyframes", 100, [this](const stereo_fabmap_slam::KeyframeConstPtr& m) { Push(m); });
  place_subscriber_ = node.subscribe<stereo_fabmap_slam::PlaceResult>(
      "place_results", 100, [this](const stereo_fabmap_slam::PlaceResultConstPtr& m) { Push(m); });
  edge_subscriber_ = node.subscribe<stereo_fabmap_slam::LoopEdge>(
      "relocalization_edges", 100,
      [this](const stereo_fabmap_slam::LoopEdgeConstPtr& m) { Push(m); });
  loaded_subscriber_ = node.subscribe<stereo_fabmap_slam::MapLoaded>(
      "map_loaded", 1, [this](const stereo_fabmap_slam::MapLoadedConstPtr& m) {
        Push(ros_wiring::MapFileLoaded{m->path});
      });
  mode_subscriber_ =
      node.subscribe<std_msgs::String>("mode", 1, [this](const std_msgs::StringConstPtr& m) {
        if (const auto mode = pipeline::ParseSlamMode(m->data)) Push(*mode);
      });
  correction_subscriber_ = node.subscribe<geometry_msgs::TransformStamped>(
      "map_to_odom_correction", 10, [this](const geometry_msgs::TransformStampedConstPtr& m) {
        Push(pipeline::LocalizationCorrectionInput{
            ros_conversions::FromTransformMessage(m->transform)});
      });
  // map -> odom is broadcast steadily, not only when it changes, so that tf can look up any
  // recent time without extrapolating. A user whose map -> odom comes from elsewhere turns the
  // package's tf off.
  if (private_node.param("publish_tf", true)) {
    tf_timer_ =
        node.createWallTimer(ros::WallDuration(1.0 / tf_rate), &BackendNodelet::OnTfTimer, this);
  }
}

void BackendNodelet::Work() {
  while (const std::optional<std::deque<ros_wiring::BackendInput>> waiting = inputs_.TakeAll()) {
    // The stage takes everything that waited at once (MappingStage::Take: under load it adjusts
    // the newest of the waiting keyframes together).
    std::vector<pipeline::MappingInput> batch;
    std::vector<std_msgs::Header> headers;  // of the batch's inputs, for the keyframe updates
    for (const ros_wiring::BackendInput& input : *waiting) {
      try {
        batch.push_back(ros_wiring::ToMappingInput(input));
        headers.push_back(ros_wiring::HeaderOf(input));
      } catch (const std::exception& error) {
        NODELET_ERROR("input skipped: %s", error.what());
      }
    }
    const pipeline::MappingBatchResult result = stage_->Take(batch);
    if (!result.falling_behind.empty()) {
      NODELET_WARN_THROTTLE(5, "%s", result.falling_behind.c_str());
    }
    for (const std::string& warning : result.warnings) NODELET_WARN("%s", warning.c_str());
    for (const std::string& news : result.news) NODELET_INFO("%s", news.c_str());
    ros::Time stamp;
    for (const auto& [index, mapped] : result.keyframes) {
      stereo_fabmap_slam::KeyframeUpdate update = ros_conversions::ToMappedKeyframeMessage(mapped);
      update.header = headers[index];
      update_publisher_.publish(update);
      stamp = headers[index].stamp;
    }
    {
      std::lock_guard<std::mutex> lock(map_to_odom_mutex_);
      map_to_odom_ = stage_->MapToOdom();
    }
    if (!result.map_changed) continue;
    stereo_fabmap_slam::MapGraph message = ros_conversions::ToMapGraphMessage(*stage_);
    message.header.stamp = stamp.isZero() ? ros::Time::now() : stamp;
    message.header.frame_id = map_frame_;
    graph_publisher_.publish(message);
  }
}

void BackendNodelet::OnTfTimer(const ros::WallTimerEvent&) {
  geometry_msgs::TransformStamped transform;
  {
    std::lock_guard<std::mutex> lock(map_to_odom_mutex_);
    transform.transform = ros_conversions::ToTransformMessage(map_to_odom_);
  }
  transform.header.frame_id = map_frame_;
  transform.child_frame_id = odom_frame_;
  const ros::Time now = ros::Time::now();
  const double wall = ros::WallTime::now().toSec();
  if (now > last_tf_stamp_) {
    transform.header.stamp = now;
  } else {
    // On simulated time the clock may stand still (a bag paused, ended, or slower than the
    // timer): the same stamp again would only make tf listeners warn. Once a second, the
    // transform a nanosecond after the last (TransformRepeater), for listeners started since.
    const std::vector<geometry_msgs::TransformStamped> due = repeater_.Due(wall, now);
    if (due.empty()) return;
    transform.header.stamp = due.front().header.stamp;
  }
  last_tf_stamp_ = transform.header.stamp;
  tf_broadcaster_->sendTransform(transform);
  repeater_.Sent(transform, wall);
}

}  // namespace stereo_fabmap_slam

PLUGINLIB_EXPORT_CLASS(stereo_fabmap_slam::BackendNodelet, nodelet::Nodelet)
