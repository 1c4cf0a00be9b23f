// LoopDetector: the place stage (pipeline::PlaceStage) in the nodelet graph. Keyframes and the
// Backend's answers to them (keyframe_updates) in; a place result per mapped keyframe
// (place_results) and relocalization edges out; the map's snapshot from map_graph. Services:
// detect_loop, relocalize_frame (the StereoTracker's), save_map, load_map (and ~map_file at
// start, ~save_map at the end), set_mode (and ~mode), announced as map_loaded and mode. The stage
// decides; this file pairs each keyframe with its answer, converts, calls and publishes. A map
// file or mode it refuses at start leaves it running with an empty map in mapping mode.
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <thread>

#include <nodelet/nodelet.h>
#include <ros/callback_queue.h>
#include <ros/ros.h>
#include <std_msgs/String.h>
#include <stereo_fabmap_slam/DetectLoop.h>
#include <stereo_fabmap_slam/MapFile.h>
#include <stereo_fabmap_slam/SetMode.h>
#include <pluginlib/class_list_macros.hpp>

#include "place_wiring.h"
#include "ros_conversions.h"
#include "stage_conversions.h"
#include "stereo_fabmap_slam/map/map_file.h"

namespace stereo_fabmap_slam {

class LoopDetectorNodelet : public nodelet::Nodelet {
 public:
  ~LoopDetectorNodelet() override {
    if (relocalize_spinner_) relocalize_spinner_->stop();
    relocalize_service_.shutdown();  // before its queue
    pairing_.Stop();
    if (worker_.joinable()) worker_.join();
    if (parameters_.save_map_at_exit.empty()) return;
    stereo_fabmap_slam::MapFile::Request request;
    stereo_fabmap_slam::MapFile::Response response;
    request.path = parameters_.save_map_at_exit;
    OnSaveMap(request, response);
    ROS_INFO_STREAM("[loop_detector] ~save_map " << request.path << ": " << response.message);
  }

 private:
  void onInit() override;
  void Work();
  // Replaces the map by a file's and announces it; throws (the map is kept) for a file that is
  // damaged or does not fit. Call with mutex_.
  std::size_t LoadMap(const std::string& path);
  bool SetMode(const std::string& name);  // announces it; false for an unknown name
  std::shared_ptr<const pipeline::MapSnapshot> Map() {
    std::lock_guard<std::mutex> lock(map_mutex_);
    return map_;
  }
  bool OnDetectLoop(stereo_fabmap_slam::DetectLoop::Request& request,
                    stereo_fabmap_slam::DetectLoop::Response& response);
  bool OnRelocalizeFrame(stereo_fabmap_slam::RelocalizeFrame::Request& request,
                         stereo_fabmap_slam::RelocalizeFrame::Response& response);
  bool OnSaveMap(stereo_fabmap_slam::MapFile::Request& request,
                 stereo_fabmap_slam::MapFile::Response& response);
  bool OnLoadMap(stereo_fabmap_slam::MapFile::Request& request,
                 stereo_fabmap_slam::MapFile::Response& response);
  bool OnSetMode(stereo_fabmap_slam::SetMode::Request& request,
                 stereo_fabmap_slam::SetMode::Response& response) {
    response.success = SetMode(request.mode);
    response.message = response.success
                           ? "mode " + request.mode
                           : "unknown mode '" + request.mode + "' (mapping, localization)";
    return true;
  }

  ros_wiring::PlaceParameters parameters_;
  std::mutex mutex_;  // the stage: the worker and the services share it
  ros_wiring::PlaceStageHolder stage_{parameters_};
  std::mutex map_mutex_;
  std::shared_ptr<const pipeline::MapSnapshot> map_ = std::make_shared<pipeline::MapSnapshot>();
  ros_wiring::KeyframePairing pairing_;
  std::thread worker_;
  ros::Subscriber keyframe_subscriber_, update_subscriber_, graph_subscriber_;
  ros::Publisher place_publisher_, edge_publisher_, loaded_publisher_, mode_publisher_;
  // relocalize_frame runs on a queue and thread of its own: the StereoTracker calls it from its
  // tracking thread, which must not wait for a free thread of the manager's pool. The queue
  // outlives the server advertised on it.
  ros::CallbackQueue relocalize_queue_;
  std::unique_ptr<ros::AsyncSpinner> relocalize_spinner_;
  ros::ServiceServer detect_service_, relocalize_service_, save_service_, load_service_,
      mode_service_;
};

void LoopDetectorNodelet::onInit() {
  ros::NodeHandle& node = getNodeHandle();
  try {  // before any ROS object exists: a throw unloads cleanly
    parameters_ = ros_wiring::ReadPlaceParameters(getPrivateNodeHandle());
  } catch (const std::exception& error) {
    NODELET_FATAL_STREAM("bad configuration: " << error.what());
    throw;
  }
  NODELET_INFO_STREAM("vocabulary " << parameters_.place.vocabulary_directory
                                    << "; options in force:\n"
                                    << parameters_.printed);
  place_publisher_ = node.advertise<stereo_fabmap_slam::PlaceResult>("place_results", 100);
  edge_publisher_ = node.advertise<stereo_fabmap_slam::LoopEdge>("relocalization_edges", 100);
  loaded_publisher_ = node.advertise<stereo_fabmap_slam::MapLoaded>("map_loaded", 1, true);
  mode_publisher_ = node.advertise<std_msgs::String>("mode", 1, true);
  // A refused ~mode or ~map_file leaves the node running, empty and mapping: the odometry goes
  // on, and load_map or set_mode can put it right without a restart.
  if (!SetMode(parameters_.mode)) {
    NODELET_ERROR("~mode '%s' is not a mode (mapping, localization): mapping",
                  parameters_.mode.c_str());
    SetMode("mapping");
  }
  if (!parameters_.map_file.empty()) {
    std::lock_guard<std::mutex> lock(mutex_);
    try {
      NODELET_INFO("map %s loaded: %zu keyframes", parameters_.map_file.c_str(),
                   LoadMap(parameters_.map_file));
    } catch (const std::exception& error) {
      NODELET_ERROR("~map_file refused: %s; running with an empty map in mapping mode",
                    error.what());
      SetMode("mapping");
    }
  }
  save_service_ = node.advertiseService("save_map", &LoopDetectorNodelet::OnSaveMap, this);
  load_service_ = node.advertiseService("load_map", &LoopDetectorNodelet::OnLoadMap, this);
  mode_service_ = node.advertiseService("set_mode", &LoopDetectorNodelet::OnSetMode, this);
  detect_service_ = node.advertiseService("detect_loop", &LoopDetectorNodelet::OnDetectLoop, this);
  ros::NodeHandle relocalize_node(node);
  relocalize_node.setCallbackQueue(&relocalize_queue_);
  relocalize_service_ = relocalize_node.advertiseService(
      "relocalize_frame", &LoopDetectorNodelet::OnRelocalizeFrame, this);
  relocalize_spinner_ = std::make_unique<ros::AsyncSpinner>(1, &relocalize_queue_);
  relocalize_spinner_->start();
  graph_subscriber_ = node.subscribe<stereo_fabmap_slam::MapGraph>(
      "map_graph", 1, [this](const stereo_fabmap_slam::MapGraphConstPtr& graph) {
        auto map =
            std::make_shared<pipeline::MapSnapshot>(ros_conversions::FromMapGraphMessage(*graph));
        std::lock_guard<std::mutex> lock(map_mutex_);
        map_ = std::move(map);
      });
  worker_ = std::thread(&LoopDetectorNodelet::Work, this);
  keyframe_subscriber_ = node.subscribe<stereo_fabmap_slam::Keyframe>(
      "keyframes", 100,
      [this](const stereo_fabmap_slam::KeyframeConstPtr& m) { pairing_.AddKeyframe(m); });
  update_subscriber_ = node.subscribe<stereo_fabmap_slam::KeyframeUpdate>(
      "keyframe_updates", 100,
      [this](const stereo_fabmap_slam::KeyframeUpdateConstPtr& m) { pairing_.AddUpdate(m); });
}

void LoopDetectorNodelet::Work() {
  while (std::optional<ros_wiring::KeyframePairing::Pair> pair = pairing_.Take()) {
    if (!pair->keyframe) {
      NODELET_WARN(
          "keyframe %lu joined the map, but its keyframe message never arrived "
          "(restarted while the tracker ran?): it is no place",
          static_cast<unsigned long>(pair->update->keyframe_id));
      continue;
    }
    try {
      std::lock_guard<std::mutex> lock(mutex_);
      // A LoopDetector (re)started while the tracker runs: say what its places do not cover.
      if (stage_.get() == nullptr && pair->keyframe->id > 0) {
        NODELET_WARN(
            "first keyframe received is %lu: the keyframes before it are not places "
            "of this LoopDetector (restarted while the tracker ran?)",
            static_cast<unsigned long>(pair->keyframe->id));
      }
      pipeline::PlaceStage& stage = stage_.For(ros_conversions::CameraOfKeyframe(*pair->keyframe));
      const pipeline::MappedKeyframe mapped =
          ros_conversions::FromMappedKeyframeMessage(*pair->update);
      stage.AddKeyframe(ros_conversions::FromKeyframeMessage(*pair->keyframe), mapped);
      if (!mapped.in_map_graph) continue;
      const pipeline::PlaceResult result = stage.DetectLoop(mapped.keyframe_id);
      stereo_fabmap_slam::PlaceResult message = ros_conversions::ToPlaceResultMessage(result);
      message.header.frame_id = pair->keyframe->header.frame_id;
      place_publisher_.publish(message);
      if (const auto& loop = result.detection.loop) {
        NODELET_INFO("loop: keyframe %ld -> %ld, %d inliers, p = %.2f",
                     static_cast<long>(loop->query_id), static_cast<long>(loop->match_id),
                     loop->inliers, loop->probability);
      }
    } catch (const std::exception& error) {
      NODELET_WARN_THROTTLE(5, "keyframe %lu not detected: %s",
                            static_cast<unsigned long>(pair->keyframe->id), error.what());
    }
  }
}

std::size_t LoopDetectorNodelet::LoadMap(const std::string& path) {
  const map::SavedMap saved = map::LoadMapFile(path);
  const pipeline::LoadedMap loaded = stage_.Load(saved);
  // Until the Backend publishes its graph rebuilt from the same file, the map is the file's.
  auto map = std::make_shared<pipeline::MapSnapshot>(ros_wiring::SnapshotOfSavedMap(saved));
  {
    std::lock_guard<std::mutex> lock(map_mutex_);
    map_ = std::move(map);
  }
  loaded_publisher_.publish(ros_conversions::ToMapLoadedMessage(path, loaded));
  return loaded.keyframes;
}

bool LoopDetectorNodelet::SetMode(const std::string& name) {
  if (!pipeline::ParseSlamMode(name)) return false;
  std_msgs::String message;
  message.data = name;
  mode_publisher_.publish(message);
  NODELET_INFO("mode %s", name.c_str());
  return true;
}

bool LoopDetectorNodelet::OnDetectLoop(stereo_fabmap_slam::DetectLoop::Request& request,
                                       stereo_fabmap_slam::DetectLoop::Response& response) {
  pipeline::LoopQuery query;
  query.stored_id = request.keyframe_id;
  query.add = request.add_to_map;
  std::lock_guard<std::mutex> lock(mutex_);
  try {
    if (query.stored_id < 0)
      query.keyframe = ros_conversions::FromKeyframeMessage(request.keyframe);
    response.message = pipeline::LoopQueryRefusal(query, stage_.get());
    if (!response.message.empty()) return true;
    pipeline::PlaceStage& stage =
        query.stored_id >= 0 ? *stage_.get()
                             : stage_.For(ros_conversions::CameraOfKeyframe(request.keyframe));
    ros_wiring::FillDetectLoopResponse(stage.Answer(query), &response);
  } catch (const std::exception& error) {
    response.success = false;
    response.message = error.what();
  }
  return true;
}

bool LoopDetectorNodelet::OnRelocalizeFrame(
    stereo_fabmap_slam::RelocalizeFrame::Request& request,
    stereo_fabmap_slam::RelocalizeFrame::Response& response) {
  const std::shared_ptr<const pipeline::MapSnapshot> map = Map();
  std::lock_guard<std::mutex> lock(mutex_);
  response.keyframe_id = -1;
  try {
    if (stage_.empty()) {
      response.status = "empty map";
      response.message = "the map is empty";
      return true;
    }
    const pipeline::RelocalizationAnswer answer =
        stage_.get()->Relocalize(ros_conversions::FromRelocalizeFrameRequest(request), *map);
    response = ros_conversions::ToRelocalizeFrameResponse(answer);
    if (answer.edge) {
      stereo_fabmap_slam::LoopEdge edge = response.edge;
      edge.header = request.frame.header;
      edge_publisher_.publish(edge);
      NODELET_INFO("relocalized: keyframe %ld joined to %ld, %d inliers",
                   static_cast<long>(answer.edge->query_id),
                   static_cast<long>(answer.edge->match_id), answer.edge->inliers);
    }
  } catch (const std::exception& error) {
    response.success = false;
    response.status = "error";
    response.message = error.what();
  }
  return true;
}

bool LoopDetectorNodelet::OnSaveMap(stereo_fabmap_slam::MapFile::Request& request,
                                    stereo_fabmap_slam::MapFile::Response& response) {
  const std::shared_ptr<const pipeline::MapSnapshot> map = Map();
  std::lock_guard<std::mutex> lock(mutex_);
  if (stage_.empty()) {
    response.message = "the map is empty";
    return true;
  }
  try {
    const map::SavedMap saved = stage_.get()->Save(*map, stage_.camera());
    map::SaveMapFile(request.path, saved);
    response.success = true;
    response.keyframes = static_cast<std::uint32_t>(saved.keyframes.size());
    response.message = "saved " + std::to_string(saved.keyframes.size()) + " keyframes and " +
                       std::to_string(saved.edges.size()) + " loop and relocalization edges";
  } catch (const std::exception& error) {
    response.message = error.what();
  }
  return true;
}

bool LoopDetectorNodelet::OnLoadMap(stereo_fabmap_slam::MapFile::Request& request,
                                    stereo_fabmap_slam::MapFile::Response& response) {
  std::lock_guard<std::mutex> lock(mutex_);
  try {
    response.keyframes = static_cast<std::uint32_t>(LoadMap(request.path));
    response.success = true;
    response.message = "loaded " + std::to_string(response.keyframes) + " keyframes";
    NODELET_INFO("map %s loaded: %u keyframes", request.path.c_str(), response.keyframes);
  } catch (const std::exception& error) {
    response.message = std::string(error.what()) + "; the map is unchanged";
  }
  return true;
}

}  // namespace stereo_fabmap_slam

PLUGINLIB_EXPORT_CLASS(stereo_fabmap_slam::LoopDetectorNodelet, nodelet::Nodelet)
