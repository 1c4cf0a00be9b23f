// Backend: keyframes and loop edges in; windowed bundle adjustment (odom frame) and the pose
// graph (map frame) in a worker thread it owns; keyframe_updates, map_graph and tf map -> odom
// out. A map loaded by the LoopDetector (map_loaded) replaces the pose graph; in localization
// mode (the LoopDetector's mode topic) the graph is not extended and map -> odom is the
// StereoTracker's latest relocalization (map_to_odom_correction). The algorithms are
// backend::LocalBundleAdjuster and backend::PoseGraph.
#include <atomic>
#include <condition_variable>
#include <deque>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <thread>
#include <vector>

#include <geometry_msgs/TransformStamped.h>
#include <nodelet/nodelet.h>
#include <ros/ros.h>
#include <std_msgs/String.h>
#include <stereo_fabmap_slam/MapLoaded.h>
#include <tf2_ros/transform_broadcaster.h>
#include <pluginlib/class_list_macros.hpp>

#include "parameter_reader.h"
#include "ros_conversions.h"
#include "stereo_fabmap_slam/backend/local_bundle_adjuster.h"
#include "stereo_fabmap_slam/backend/pose_graph.h"
#include "stereo_fabmap_slam/map/map_file.h"
#include "stereo_fabmap_slam/pipeline/loop_closing.h"

namespace stereo_fabmap_slam {

class BackendNodelet : public nodelet::Nodelet {
 public:
  ~BackendNodelet() override;

 private:
  void onInit() override;
  void OnKeyframe(const stereo_fabmap_slam::KeyframeConstPtr& keyframe);
  void OnLoopEdge(const stereo_fabmap_slam::LoopEdgeConstPtr& loop);
  void OnTfTimer(const ros::WallTimerEvent&);
  void OnMapLoaded(const stereo_fabmap_slam::MapLoadedConstPtr& message);
  void OnMode(const std_msgs::StringConstPtr& message);
  void OnCorrection(const geometry_msgs::TransformStampedConstPtr& message);
  void Work();
  // Adds to the graph the loop edges whose keyframes it has (the LoopDetector may be ahead of
  // the bundle adjustment); true if any was added. The others wait.
  struct Edge {
    map::LoopEdge edge;
    backend::PoseGraphEdgeType type;  // a loop, or a relocalization
  };
  bool AddReadyLoops(backend::PoseGraph* graph, std::deque<Edge>* loops);

  backend::BundleAdjustmentOptions options_;
  backend::PoseGraphOptions pose_graph_options_;
  std::string map_frame_, odom_frame_;
  ros::Subscriber keyframe_subscriber_, loop_subscriber_, map_loaded_subscriber_, mode_subscriber_,
      correction_subscriber_;
  ros::Publisher update_publisher_, graph_publisher_;
  std::unique_ptr<tf2_ros::TransformBroadcaster> tf_broadcaster_;
  ros::WallTimer tf_timer_;
  ros::Time last_tf_stamp_;  // only the timer's thread touches it

  std::mutex mutex_;
  std::condition_variable wake_;
  // Keyframes and loop edges not yet in the map. Never bounded by dropping: a keyframe missing
  // from the map would leave a hole in the graph. Under load the worker adjusts the newest of
  // them together and skips the optimisations in between (see Work()).
  std::deque<stereo_fabmap_slam::KeyframeConstPtr> queue_;
  std::deque<Edge> loop_queue_;
  std::optional<std::string> map_to_load_;    // a loaded map's file, for the worker
  std::atomic<bool> localization_{false};     // localization mode: the graph is not extended
  std::atomic<bool> mapping_resumed_{false};  // set when localization mode ends
  bool stopping_ = false;
  std::thread worker_;

  std::mutex map_to_odom_mutex_;
  Eigen::Isometry3d map_to_odom_ = Eigen::Isometry3d::Identity();  // the graph's latest
};

void BackendNodelet::onInit() {
  ros::NodeHandle& private_node = getPrivateNodeHandle();
  try {
    options_ = ros_parameters::ReadModuleOptions(private_node, options_);
    pose_graph_options_ = ros_parameters::ReadModuleOptions(private_node, pose_graph_options_);
  } catch (const std::exception& error) {
    NODELET_FATAL_STREAM("bad configuration: " << error.what());
    throw;
  }
  NODELET_INFO_STREAM("options in force:\n"
                      << ros_parameters::PrintedOptions(options_)
                      << ros_parameters::PrintedOptions(pose_graph_options_));
  map_frame_ = private_node.param<std::string>("map_frame", "map");
  odom_frame_ = private_node.param<std::string>("odom_frame", "odom");
  const double tf_rate = private_node.param("tf_rate", 20.0);
  // A user whose map -> odom comes from elsewhere turns the package's tf off.
  const bool publish_tf = private_node.param("publish_tf", true);

  ros::NodeHandle& node = getNodeHandle();
  update_publisher_ = node.advertise<stereo_fabmap_slam::KeyframeUpdate>("keyframe_updates", 100);
  graph_publisher_ = node.advertise<stereo_fabmap_slam::MapGraph>("map_graph", 1, true);
  tf_broadcaster_ = std::make_unique<tf2_ros::TransformBroadcaster>();
  worker_ = std::thread(&BackendNodelet::Work, this);
  keyframe_subscriber_ = node.subscribe("keyframes", 100, &BackendNodelet::OnKeyframe, this);
  loop_subscriber_ = node.subscribe("loop_edges", 100, &BackendNodelet::OnLoopEdge, this);
  map_loaded_subscriber_ = node.subscribe("map_loaded", 1, &BackendNodelet::OnMapLoaded, this);
  mode_subscriber_ = node.subscribe("mode", 1, &BackendNodelet::OnMode, this);
  correction_subscriber_ =
      node.subscribe("map_to_odom_correction", 10, &BackendNodelet::OnCorrection, this);
  // map -> odom is broadcast steadily, not only when it changes, so that tf can look up any
  // recent time without extrapolating.
  if (publish_tf) {
    tf_timer_ =
        node.createWallTimer(ros::WallDuration(1.0 / tf_rate), &BackendNodelet::OnTfTimer, this);
  }
}

BackendNodelet::~BackendNodelet() {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    stopping_ = true;
  }
  wake_.notify_all();
  if (worker_.joinable()) worker_.join();
}

void BackendNodelet::OnKeyframe(const stereo_fabmap_slam::KeyframeConstPtr& keyframe) {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    queue_.push_back(keyframe);
  }
  wake_.notify_one();
}

void BackendNodelet::OnLoopEdge(const stereo_fabmap_slam::LoopEdgeConstPtr& loop) {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    loop_queue_.push_back({ros_conversions::FromLoopEdgeMessage(*loop),
                           loop->relocalization ? backend::PoseGraphEdgeType::kRelocalization
                                                : backend::PoseGraphEdgeType::kLoop});
  }
  wake_.notify_one();
}

void BackendNodelet::OnMapLoaded(const stereo_fabmap_slam::MapLoadedConstPtr& message) {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    map_to_load_ = message->path;
  }
  wake_.notify_one();
}

void BackendNodelet::OnMode(const std_msgs::StringConstPtr& message) {
  const bool localization = message->data == "localization";
  // Back to mapping: the keyframes of the localization time were not added, and a loss among
  // them is unknown here, so the next keyframe starts a new piece of odometry.
  if (localization_ && !localization) mapping_resumed_ = true;
  localization_ = localization;
}

void BackendNodelet::OnCorrection(const geometry_msgs::TransformStampedConstPtr& message) {
  if (!localization_) return;  // mapping: the pose graph owns map -> odom
  std::lock_guard<std::mutex> lock(map_to_odom_mutex_);
  map_to_odom_ = ros_conversions::FromTransformMessage(message->transform);
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

void BackendNodelet::Work() {
  std::unique_ptr<backend::LocalBundleAdjuster> adjuster;
  backend::PoseGraph graph(pose_graph_options_);
  std::deque<Edge> pending_loops;    // their keyframes have not arrived yet
  bool next_starts_new_map = false;  // after a load: this run's odometry is a new piece
  // Keyframes below this id are a loaded map's: this run's bundle adjustment never moves them,
  // and a keyframe of this run with such an id was made before the load.
  std::int64_t loaded_below = 0;
  while (true) {
    std::deque<stereo_fabmap_slam::KeyframeConstPtr> waiting;
    std::optional<std::string> load;
    {
      std::unique_lock<std::mutex> lock(mutex_);
      wake_.wait(lock, [&] {
        return stopping_ || !queue_.empty() || !loop_queue_.empty() || map_to_load_;
      });
      if (stopping_) return;
      waiting.swap(queue_);
      pending_loops.insert(pending_loops.end(), loop_queue_.begin(), loop_queue_.end());
      loop_queue_.clear();
      load.swap(map_to_load_);
    }
    if (load) {
      // The LoopDetector checked the file; the graph is rebuilt from the same file.
      try {
        const map::SavedMap saved = map::LoadMapFile(*load);
        graph = pipeline::LoopClosing::RestorePoseGraph(saved, pose_graph_options_);
        pending_loops.clear();
        next_starts_new_map = true;
        adjuster.reset();  // this run's window, with ids the map may use too, starts afresh
        for (const map::SavedKeyframe& keyframe : saved.keyframes) {
          loaded_below = std::max(loaded_below, keyframe.keyframe.id + 1);
        }
        NODELET_INFO("pose graph of %s: %zu keyframes", load->c_str(), graph.size());
      } catch (const std::exception& error) {
        NODELET_ERROR("map %s not loaded into the pose graph: %s", load->c_str(), error.what());
      }
    }
    if (waiting.size() > 1) {
      NODELET_WARN_THROTTLE(5,
                            "bundle adjustment falls behind: %zu keyframes added in one "
                            "optimisation",
                            waiting.size());
    }
    // Every keyframe enters the map; only the newest is followed by an optimisation, whose
    // window covers the others.
    ros::Time stamp;
    while (!waiting.empty()) {
      const stereo_fabmap_slam::KeyframeConstPtr message = waiting.front();
      waiting.pop_front();
      const bool optimise = waiting.empty();
      try {
        if (!adjuster) {
          adjuster = std::make_unique<backend::LocalBundleAdjuster>(
              options_, ros_conversions::CameraOfKeyframe(*message));
          // A Backend (re)started while the tracker runs: say what this map does not have.
          if (message->id > 0 && loaded_below == 0) {
            NODELET_WARN(
                "first keyframe received is %lu: the keyframes before it are not in "
                "this Backend's map (restarted while the tracker ran?); optimising "
                "from here, map -> odom starts at identity",
                static_cast<unsigned long>(message->id));
          }
        }
        if (static_cast<std::int64_t>(message->id) < loaded_below) continue;  // before a load
        const map::Keyframe keyframe = ros_conversions::FromKeyframeMessage(*message);
        const map::KeyframeUpdate update = adjuster->AddKeyframe(keyframe, optimise);
        // Keyframes made before a map was loaded (ids below the map's) stay out of its graph.
        if (mapping_resumed_.exchange(false)) next_starts_new_map = true;
        if (!localization_ && keyframe.id > graph.last_id()) {
          graph.AddKeyframe(keyframe.id, keyframe.T_world_camera,
                            keyframe.starts_new_map || next_starts_new_map);
          next_starts_new_map = false;
        }
        for (const auto& [id, pose] : update.keyframe_poses) {
          if (id >= loaded_below && graph.Contains(id)) graph.UpdateOdometryPose(id, pose);
        }
        stamp = message->header.stamp;
        if (!optimise) continue;
        stereo_fabmap_slam::KeyframeUpdate update_message =
            ros_conversions::ToKeyframeUpdateMessage(update);
        update_message.header = message->header;
        update_publisher_.publish(update_message);
      } catch (const std::exception& error) {
        NODELET_WARN_THROTTLE(5, "keyframe %lu skipped: %s",
                              static_cast<unsigned long>(message->id), error.what());
      }
    }
    if (AddReadyLoops(&graph, &pending_loops)) {
      const backend::PoseGraphSummary summary = graph.Optimize();
      NODELET_INFO("pose graph: %zu of %zu keyframes optimised (%s) in %d iterations",
                   summary.moved_keyframes, graph.size(),
                   summary.local ? "near loops that agree with the map" : "whole graph",
                   summary.iterations);
    }
    if (!localization_ && graph.size() > 0) {
      std::lock_guard<std::mutex> lock(map_to_odom_mutex_);
      map_to_odom_ = graph.MapToOdom();
    }
    if (!stamp.isZero() || graph.size() > 0) {
      stereo_fabmap_slam::MapGraph message = ros_conversions::ToMapGraphMessage(graph);
      message.header.stamp = stamp.isZero() ? ros::Time::now() : stamp;
      message.header.frame_id = map_frame_;
      graph_publisher_.publish(message);
    }
  }
}

bool BackendNodelet::AddReadyLoops(backend::PoseGraph* graph, std::deque<Edge>* loops) {
  bool added = false;
  for (auto it = loops->begin(); it != loops->end();) {
    if (!graph->Contains(it->edge.query_id) || !graph->Contains(it->edge.match_id)) {
      ++it;
      continue;
    }
    try {
      graph->AddLoop(it->edge, it->type);
      added = true;
    } catch (const std::exception& error) {
      NODELET_WARN("loop edge %ld -> %ld ignored: %s", static_cast<long>(it->edge.query_id),
                   static_cast<long>(it->edge.match_id), error.what());
    }
    it = loops->erase(it);
  }
  return added;
}

}  // namespace stereo_fabmap_slam

PLUGINLIB_EXPORT_CLASS(stereo_fabmap_slam::BackendNodelet, nodelet::Nodelet)
