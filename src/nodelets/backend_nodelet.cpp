// Backend: the mapping stage (pipeline::MappingStage) in the nodelet graph. Keyframes, the
// LoopDetector's place results and relocalization edges, loaded maps, the mode and localization's
// map -> odom in; keyframe_updates (one per keyframe), map_graph and tf map -> odom out. The
// stage decides; this file queues every input in arrival order for a worker thread it owns,
// converts, calls and publishes.
#include <condition_variable>
#include <deque>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <thread>
#include <variant>

#include <geometry_msgs/TransformStamped.h>
#include <nodelet/nodelet.h>
#include <ros/ros.h>
#include <std_msgs/String.h>
#include <stereo_fabmap_slam/MapLoaded.h>
#include <tf2_ros/transform_broadcaster.h>
#include <pluginlib/class_list_macros.hpp>

#include "parameter_reader.h"
#include "ros_conversions.h"
#include "stage_conversions.h"
#include "stereo_fabmap_slam/map/map_file.h"
#include "stereo_fabmap_slam/pipeline/mapping_stage.h"
#include "tracker_wiring.h"

namespace stereo_fabmap_slam {

class BackendNodelet : public nodelet::Nodelet {
 public:
  ~BackendNodelet() override {
    {
      std::lock_guard<std::mutex> lock(mutex_);
      stopping_ = true;
    }
    wake_.notify_all();
    if (worker_.joinable()) worker_.join();
  }

 private:
  struct LoadMap {
    std::string path;
  };
  struct Correction {
    Eigen::Isometry3d T_map_odom;
  };
  // Every input, in the order it arrived: the stage takes them so.
  using Input =
      std::variant<stereo_fabmap_slam::KeyframeConstPtr, stereo_fabmap_slam::PlaceResultConstPtr,
                   stereo_fabmap_slam::LoopEdgeConstPtr, LoadMap, pipeline::SlamMode, Correction>;

  void onInit() override;
  void Push(Input input) {
    {
      std::lock_guard<std::mutex> lock(mutex_);
      inputs_.push_back(std::move(input));
    }
    wake_.notify_one();
  }
  void Work();
  // Returns whether the map changed (map_graph is published again).
  bool Apply(const Input& input, bool optimise, ros::Time* stamp);
  void OnTfTimer(const ros::WallTimerEvent&);

  std::string map_frame_, odom_frame_;
  std::optional<pipeline::MappingStage> stage_;  // the worker's only
  ros::Subscriber keyframe_subscriber_, place_subscriber_, edge_subscriber_, loaded_subscriber_,
      mode_subscriber_, correction_subscriber_;
  ros::Publisher update_publisher_, graph_publisher_;
  std::unique_ptr<tf2_ros::TransformBroadcaster> tf_broadcaster_;
  ros::WallTimer tf_timer_;
  ros::Time last_tf_stamp_;  // only the timer's thread touches it
  std::mutex mutex_;
  std::condition_variable wake_;
  // Never bounded by dropping: a keyframe missing from the map would leave a hole in the graph.
  // Under load the worker adjusts the newest of the waiting keyframes together (see Work()).
  std::deque<Input> inputs_;
  bool stopping_ = false;
  std::thread worker_;
  std::mutex map_to_odom_mutex_;
  Eigen::Isometry3d map_to_odom_ = Eigen::Isometry3d::Identity();
};

void BackendNodelet::onInit() {
  ros::NodeHandle& private_node = getPrivateNodeHandle();
  backend::BundleAdjustmentOptions options;
  backend::PoseGraphOptions pose_graph_options;
  try {  // before any ROS object exists: a throw unloads cleanly
    options = ros_parameters::ReadModuleOptions(private_node, options);
    pose_graph_options = ros_parameters::ReadModuleOptions(private_node, pose_graph_options);
  } catch (const std::exception& error) {
    NODELET_FATAL_STREAM("bad configuration: " << error.what());
    throw;
  }
  NODELET_INFO_STREAM("options in force:\n"
                      << ros_parameters::PrintedOptions(options)
                      << ros_parameters::PrintedOptions(pose_graph_options));
  stage_.emplace(options, pose_graph_options, ros_wiring::SteadyMilliseconds);
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
      "map_loaded", 1,
      [this](const stereo_fabmap_slam::MapLoadedConstPtr& m) { Push(LoadMap{m->path}); });
  mode_subscriber_ =
      node.subscribe<std_msgs::String>("mode", 1, [this](const std_msgs::StringConstPtr& m) {
        if (const auto mode = pipeline::ParseSlamMode(m->data)) Push(*mode);
      });
  correction_subscriber_ = node.subscribe<geometry_msgs::TransformStamped>(
      "map_to_odom_correction", 10, [this](const geometry_msgs::TransformStampedConstPtr& m) {
        Push(Correction{ros_conversions::FromTransformMessage(m->transform)});
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
  while (true) {
    std::deque<Input> waiting;
    {
      std::unique_lock<std::mutex> lock(mutex_);
      wake_.wait(lock, [&] { return stopping_ || !inputs_.empty(); });
      if (stopping_) return;
      waiting.swap(inputs_);
    }
    // Every keyframe enters the map; only the newest of those waiting is followed by a bundle
    // adjustment, whose window covers the others.
    std::size_t keyframes = 0, seen = 0;
    for (const Input& input : waiting) {
      keyframes += std::holds_alternative<stereo_fabmap_slam::KeyframeConstPtr>(input) ? 1 : 0;
    }
    if (keyframes > 1) {
      NODELET_WARN_THROTTLE(5,
                            "bundle adjustment falls behind: %zu keyframes added in one "
                            "optimisation",
                            keyframes);
    }
    bool changed = false;
    ros::Time stamp;
    const std::uint64_t optimisations = stage_->optimisations();
    for (const Input& input : waiting) {
      const bool keyframe = std::holds_alternative<stereo_fabmap_slam::KeyframeConstPtr>(input);
      seen += keyframe ? 1 : 0;
      try {
        changed = Apply(input, !keyframe || seen == keyframes, &stamp) || changed;
      } catch (const std::exception& error) {
        NODELET_WARN_THROTTLE(5, "input skipped: %s", error.what());
      }
    }
    for (const std::string& refused : stage_->TakeRefusedEdges())
      NODELET_WARN("%s", refused.c_str());
    if (stage_->optimisations() > optimisations) {
      const backend::PoseGraphSummary& summary = stage_->last_optimisation();
      NODELET_INFO("pose graph: %zu of %zu keyframes optimised (%s) in %d iterations",
                   summary.moved_keyframes, stage_->pose_graph().size(),
                   summary.local ? "near loops that agree with the map" : "whole graph",
                   summary.iterations);
    }
    {
      std::lock_guard<std::mutex> lock(map_to_odom_mutex_);
      map_to_odom_ = stage_->MapToOdom();
    }
    if (!changed) continue;
    stereo_fabmap_slam::MapGraph message = ros_conversions::ToMapGraphMessage(*stage_);
    message.header.stamp = stamp.isZero() ? ros::Time::now() : stamp;
    message.header.frame_id = map_frame_;
    graph_publisher_.publish(message);
  }
}

bool BackendNodelet::Apply(const Input& input, bool optimise, ros::Time* stamp) {
  if (const auto* keyframe = std::get_if<stereo_fabmap_slam::KeyframeConstPtr>(&input)) {
    const stereo_fabmap_slam::Keyframe& message = **keyframe;
    // A Backend (re)started while the tracker runs: say what this map does not have.
    if (stage_->empty() && !stage_->camera() && message.id > 0 && stage_->loaded_below() == 0) {
      NODELET_WARN(
          "first keyframe received is %lu: the keyframes before it are not in this "
          "Backend's map (restarted while the tracker ran?); optimising from here, "
          "map -> odom starts at identity",
          static_cast<unsigned long>(message.id));
    }
    const pipeline::MappedKeyframe mapped =
        stage_->AddKeyframe(ros_conversions::FromKeyframeMessage(message),
                            ros_conversions::CameraOfKeyframe(message), optimise);
    stereo_fabmap_slam::KeyframeUpdate update = ros_conversions::ToMappedKeyframeMessage(mapped);
    update.header = message.header;
    update_publisher_.publish(update);
    *stamp = message.header.stamp;
    return true;
  }
  if (const auto* place = std::get_if<stereo_fabmap_slam::PlaceResultConstPtr>(&input)) {
    const pipeline::PlaceResult result = ros_conversions::FromPlaceResultMessage(**place);
    stage_->ApplyLoopDetection(result.keyframe_id, result.detection.loop);
    return true;
  }
  if (const auto* edge = std::get_if<stereo_fabmap_slam::LoopEdgeConstPtr>(&input)) {
    stage_->AddEdge(ros_conversions::FromLoopEdgeMessage(**edge),
                    backend::PoseGraphEdgeType::kRelocalization);
    return true;
  }
  if (const auto* load = std::get_if<LoadMap>(&input)) {
    // The LoopDetector checked the file; the graph is rebuilt from the same file.
    try {
      stage_->Load(map::LoadMapFile(load->path));
      NODELET_INFO("pose graph of %s: %zu keyframes", load->path.c_str(),
                   stage_->pose_graph().size());
    } catch (const std::exception& error) {
      NODELET_ERROR("map %s not loaded into the pose graph: %s", load->path.c_str(), error.what());
    }
    return true;
  }
  if (const auto* mode = std::get_if<pipeline::SlamMode>(&input)) {
    stage_->SetMode(*mode);
    return false;
  }
  stage_->SetLocalizationCorrection(std::get<Correction>(input).T_map_odom);
  return false;
}

void BackendNodelet::OnTfTimer(const ros::WallTimerEvent&) {
  // On simulated time the clock may not have moved since the last broadcast (a bag paused or
  // slower than the timer): the same stamp again would only make tf listeners warn.
  const ros::Time now = ros::Time::now();
  if (now <= last_tf_stamp_) return;
  last_tf_stamp_ = now;
  geometry_msgs::TransformStamped transform;
  {
    std::lock_guard<std::mutex> lock(map_to_odom_mutex_);
    transform.transform = ros_conversions::ToTransformMessage(map_to_odom_);
  }
  transform.header.stamp = now;
  transform.header.frame_id = map_frame_;
  transform.child_frame_id = odom_frame_;
  tf_broadcaster_->sendTransform(transform);
}

}  // namespace stereo_fabmap_slam

PLUGINLIB_EXPORT_CLASS(stereo_fabmap_slam::BackendNodelet, nodelet::Nodelet)
