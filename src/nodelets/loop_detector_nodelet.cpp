// LoopDetector: the place stage (pipeline::PlaceStage) in the nodelet graph. Keyframes and the
// Backend's answers to them (keyframe_updates) in; a place result per mapped keyframe
// (place_results) and relocalization edges out; the map's snapshot from map_graph. Services:
// detect_loop, relocalize_frame (the StereoTracker's), save_map, load_map (and ~map_file at
// start, ~save_map at the end), set_mode (and ~mode), announced as map_loaded and mode. The
// place service (pipeline::PlaceService) decides; this file pairs each keyframe with its answer,
// converts, calls and publishes.
#include <cstdio>
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
    if (parameters_.save_map_at_exit.empty() || !places_) return;
    std::lock_guard<std::mutex> lock(mutex_);  // a service call may still be answered
    const pipeline::MapFileAnswer saved =
        places_->SaveMap(parameters_.save_map_at_exit, *places_->followed_map());
    // On stderr: when the manager unloads its nodelets, rosconsole has shut down with the node
    // and its macros print nothing, so a failed save would go unsaid.
    std::fprintf(stderr, "[loop_detector] ~save_map %s: %s\n", parameters_.save_map_at_exit.c_str(),
                 saved.message.c_str());
  }

 private:
  void onInit() override;
  void Work();
  void Announce(const pipeline::LoadedMapFile& file);
  void Announce(pipeline::SlamMode mode);
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
    const pipeline::ModeAnswer answer = pipeline::ModeNamed(request.mode);
    if (answer.mode) Announce(*answer.mode);
    response.success = answer.mode.has_value();
    response.message = answer.message;
    return true;
  }

  ros_wiring::PlaceParameters parameters_;
  std::mutex mutex_;  // the service: the worker and the services share it
  std::optional<pipeline::PlaceService> places_;  // made before any callback can run
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
  {
    std::lock_guard<std::mutex> lock(mutex_);
    places_.emplace(ros_wiring::MakePlaceService(parameters_));
    const pipeline::PlaceService::StartUp start =
        places_->Start(parameters_.mode, parameters_.map_file);
    for (const std::string& error : start.errors) NODELET_ERROR("%s", error.c_str());
    Announce(start.mode);
    if (start.map) Announce(*start.map);
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
        places_->FollowMap(
            std::make_shared<pipeline::MapSnapshot>(ros_conversions::FromMapGraphMessage(*graph)));
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
    try {
      const pipeline::MappedKeyframe mapped =
          ros_conversions::FromMappedKeyframeMessage(*pair->update);
      std::lock_guard<std::mutex> lock(mutex_);
      const pipeline::PlaceService::KeyframeOutcome outcome =
          pair->keyframe ? places_->Take(ros_conversions::FromKeyframeMessage(*pair->keyframe),
                                         ros_conversions::CameraOfKeyframe(*pair->keyframe), mapped)
                         : places_->Take(mapped);
      for (const std::string& warning : outcome.warnings) NODELET_WARN("%s", warning.c_str());
      if (!outcome.result) continue;
      const pipeline::PlaceResult& result = *outcome.result;
      stereo_fabmap_slam::PlaceResult message = ros_conversions::ToPlaceResultMessage(result);
      message.header.frame_id = pair->keyframe->header.frame_id;  // a place has its keyframe
      place_publisher_.publish(message);
      if (const auto& loop = result.detection.loop) {
        NODELET_INFO("loop: keyframe %ld -> %ld, %d inliers, p = %.2f",
                     static_cast<long>(loop->query_id), static_cast<long>(loop->match_id),
                     loop->inliers, loop->probability);
      }
    } catch (const std::exception& error) {
      NODELET_WARN_THROTTLE(5, "keyframe %lu not detected: %s",
                            static_cast<unsigned long>(pair->update->keyframe_id), error.what());
    }
  }
}

void LoopDetectorNodelet::Announce(const pipeline::LoadedMapFile& file) {
  loaded_publisher_.publish(ros_conversions::ToMapLoadedMessage(file.path, file.loaded));
  NODELET_INFO("map %s loaded: %zu keyframes", file.path.c_str(), file.loaded.keyframes);
}

void LoopDetectorNodelet::Announce(pipeline::SlamMode mode) {
  std_msgs::String message;
  message.data = pipeline::SlamModeName(mode);
  mode_publisher_.publish(message);
  NODELET_INFO("mode %s", message.data.c_str());
}

bool LoopDetectorNodelet::OnDetectLoop(stereo_fabmap_slam::DetectLoop::Request& request,
                                       stereo_fabmap_slam::DetectLoop::Response& response) {
  pipeline::LoopQuery query;
  query.stored_id = request.keyframe_id;
  query.add = request.add_to_map;
  std::lock_guard<std::mutex> lock(mutex_);
  try {
    if (query.stored_id < 0) {
      query.keyframe = ros_conversions::FromKeyframeMessage(request.keyframe);
    }
    ros_wiring::FillDetectLoopResponse(
        places_->Answer(query, ros_conversions::CameraOfKeyframe(request.keyframe)), &response);
  } catch (const std::exception& error) {
    response.success = false;
    response.message = error.what();
  }
  return true;
}

bool LoopDetectorNodelet::OnRelocalizeFrame(
    stereo_fabmap_slam::RelocalizeFrame::Request& request,
    stereo_fabmap_slam::RelocalizeFrame::Response& response) {
  std::lock_guard<std::mutex> lock(mutex_);
  response.keyframe_id = -1;
  try {
    const pipeline::RelocalizationAnswer answer = places_->Relocalize(
        ros_conversions::FromRelocalizeFrameRequest(request), *places_->followed_map());
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
  std::lock_guard<std::mutex> lock(mutex_);
  ros_wiring::FillMapFileResponse(places_->SaveMap(request.path, *places_->followed_map()),
                                  &response);
  return true;
}

bool LoopDetectorNodelet::OnLoadMap(stereo_fabmap_slam::MapFile::Request& request,
                                    stereo_fabmap_slam::MapFile::Response& response) {
  std::lock_guard<std::mutex> lock(mutex_);
  std::optional<pipeline::LoadedMapFile> loaded;
  ros_wiring::FillMapFileResponse(places_->LoadMap(request.path, &loaded), &response);
  if (loaded) Announce(*loaded);
  return true;
}

}  // namespace stereo_fabmap_slam

PLUGINLIB_EXPORT_CLASS(stereo_fabmap_slam::LoopDetectorNodelet, nodelet::Nodelet)
