// LoopDetector: keyframes in, verified loop edges out, the detect_loop service, and the
// relocalize_frame service the StereoTracker calls (after a tracking loss, and for the user's
// relocalize). It keeps the map's keyframes, so it also offers save_map, load_map (and
// ~map_file at start) and set_mode (~mode), announcing a loaded map (map_loaded) and the mode
// (mode) to the other nodelets. Everything algorithmic is place_recognition::LoopDetector,
// relocalization::Relocalizer and the map file; this file converts, queues and publishes. Map
// poses and which keyframes form one map come from the Backend's map_graph.
#include <chrono>
#include <condition_variable>
#include <deque>
#include <functional>
#include <map>
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
#include <stereo_fabmap_slam/KeyframeUpdate.h>
#include <stereo_fabmap_slam/MapFile.h>
#include <stereo_fabmap_slam/MapGraph.h>
#include <stereo_fabmap_slam/MapLoaded.h>
#include <stereo_fabmap_slam/RelocalizeFrame.h>
#include <stereo_fabmap_slam/SetMode.h>
#include <pluginlib/class_list_macros.hpp>

#include "parameter_reader.h"
#include "ros_conversions.h"
#include "stereo_fabmap_slam/backend/pose_graph.h"
#include "stereo_fabmap_slam/features/feature_factory.h"
#include "stereo_fabmap_slam/geometry/relative_pose_error.h"
#include "stereo_fabmap_slam/map/map_file.h"
#include "stereo_fabmap_slam/pipeline/loop_closing.h"
#include "stereo_fabmap_slam/pipeline/stereo_slam.h"
#include "stereo_fabmap_slam/relocalization/relocalizer.h"

namespace stereo_fabmap_slam {

class LoopDetectorNodelet : public nodelet::Nodelet {
 public:
  ~LoopDetectorNodelet() override;

 private:
  void onInit() override;
  void OnKeyframe(const stereo_fabmap_slam::KeyframeConstPtr& keyframe);
  bool OnDetectLoop(stereo_fabmap_slam::DetectLoop::Request& request,
                    stereo_fabmap_slam::DetectLoop::Response& response);
  bool OnRelocalizeFrame(stereo_fabmap_slam::RelocalizeFrame::Request& request,
                         stereo_fabmap_slam::RelocalizeFrame::Response& response);
  void OnMapGraph(const stereo_fabmap_slam::MapGraphConstPtr& graph);
  void OnKeyframeUpdate(const stereo_fabmap_slam::KeyframeUpdateConstPtr& update);
  bool OnSaveMap(stereo_fabmap_slam::MapFile::Request& request,
                 stereo_fabmap_slam::MapFile::Response& response);
  bool OnLoadMap(stereo_fabmap_slam::MapFile::Request& request,
                 stereo_fabmap_slam::MapFile::Response& response);
  bool OnSetMode(stereo_fabmap_slam::SetMode::Request& request,
                 stereo_fabmap_slam::SetMode::Response& response);
  // Loads a map file in place of the map and announces it; throws io::InputError (the map is
  // kept) for a file that is damaged or does not fit. Call with mutex_.
  std::size_t LoadMap(const std::string& path);
  // The detector for a camera (made once; the first keyframe's or a loaded map's). Call with
  // mutex_.
  void MakeDetector(const geometry::StereoCamera& camera);
  void Work();
  // The detector needs the camera, which arrives with the first keyframe. Call with mutex_.
  place_recognition::LoopDetector& Detector(const stereo_fabmap_slam::Keyframe& message);

  place_recognition::PlaceRecognitionOptions place_options_;
  place_recognition::LoopDetectorOptions detector_options_;
  features::DescriptorKind descriptor_;
  std::optional<place_recognition::LoopDetector> detector_;
  relocalization::RelocalizerOptions relocalizer_options_;
  std::optional<relocalization::Relocalizer> relocalizer_;  // made with the detector
  std::optional<geometry::StereoCamera> camera_;            // the map's camera
  backend::PoseGraphOptions pose_graph_options_;  // to check a map's graph before loading it
  pipeline::SlamMode mode_ = pipeline::SlamMode::kMapping;
  // The next keyframe added starts a new piece of odometry: after a load (the map's odometry is
  // another run's) and after localization mode (its keyframes were not added, a loss among
  // them is unknown here).
  bool next_starts_new_map_ = false;
  // Keyframes below this id belong to a loaded map: this run's bundle adjustment never moves
  // them, and an update or keyframe of this run with such an id is from before the load.
  std::int64_t loaded_below_ = 0;

  // From the latest map_graph: map poses, and the component (keyframes joined by odometry, loop
  // and relocalization edges) of each keyframe; the map is the first keyframe's component.
  struct MapView {
    std::map<std::int64_t, Eigen::Isometry3d> poses;
    std::map<std::int64_t, std::int64_t> component;  // keyframe -> its component's first id
    std::int64_t first = -1;
    Eigen::Isometry3d map_to_odom = Eigen::Isometry3d::Identity();
    std::vector<map::SavedEdge> edges;  // loop and relocalization edges
    bool InMap(std::int64_t id) const {
      const auto it = component.find(id);
      return first >= 0 && it != component.end() && it->second == component.at(first);
    }
  };
  // Builds a view from keyframe ids with map poses, the joins between them (odometry, loop and
  // relocalization edges) and the loop and relocalization edges to save.
  MapView MakeMapView(const std::vector<std::pair<std::int64_t, Eigen::Isometry3d>>& poses,
                      const std::vector<std::pair<std::int64_t, std::int64_t>>& joins,
                      std::vector<map::SavedEdge> edges,
                      const Eigen::Isometry3d& map_to_odom) const;
  std::mutex map_view_mutex_;
  MapView map_view_;

  ros::Subscriber keyframe_subscriber_, graph_subscriber_, update_subscriber_;
  ros::Publisher loop_publisher_, map_loaded_publisher_, mode_publisher_;
  // relocalize_frame runs on a queue and thread of its own: the StereoTracker calls it from its
  // image callback, which must not wait for a free thread of the manager's pool. The queue
  // outlives the server advertised on it: a server destroyed after its queue locks the queue's
  // freed mutex (boost::lock_error when the manager unloads the nodelet).
  ros::CallbackQueue relocalize_queue_;
  std::unique_ptr<ros::AsyncSpinner> relocalize_spinner_;
  ros::ServiceServer detect_service_, relocalize_service_, save_service_, load_service_,
      mode_service_;

  std::mutex mutex_;  // the detector: the worker and the service share it
  std::mutex queue_mutex_;
  std::condition_variable wake_;
  // Keyframes not yet detected. Never dropped: every keyframe must become a place. The worker
  // takes all that waited in one pass, so the queue holds what arrives during one detection.
  std::deque<stereo_fabmap_slam::KeyframeConstPtr> queue_;
  bool stopping_ = false;
  std::thread worker_;
};

void LoopDetectorNodelet::onInit() {
  ros::NodeHandle& private_node = getPrivateNodeHandle();
  try {
    const features::FeatureOptions odometry_features =
        ros_parameters::ReadModuleOptions(private_node, features::FeatureOptions());
    descriptor_ = features::CreateDescriptor(odometry_features);
    std::string fabmap_config;
    if (!private_node.getParam("fabmap_config", fabmap_config)) {
      throw std::runtime_error("set ~fabmap_config (e.g. config/fabmap.yaml)");
    }
    place_options_ =
        place_recognition::LoadPlaceRecognitionOptions(fabmap_config, odometry_features);
    detector_options_ = ros_parameters::ReadModuleOptions(private_node, detector_options_);
    relocalizer_options_ = ros_parameters::ReadModuleOptions(private_node, relocalizer_options_);
    pose_graph_options_ = ros_parameters::ReadModuleOptions(private_node, pose_graph_options_);
    // Load the vocabulary once now, so that a missing or damaged file stops start-up.
    place_recognition::Vocabulary::Load(place_options_.vocabulary_directory + "/vocabulary.bin");
  } catch (const std::exception& error) {
    NODELET_FATAL_STREAM("bad configuration: " << error.what());
    throw;
  }
  NODELET_INFO_STREAM("vocabulary " << place_options_.vocabulary_directory
                                    << "; options in force:\n"
                                    << ros_parameters::PrintedOptions(detector_options_)
                                    << ros_parameters::PrintedOptions(relocalizer_options_));
  ros::NodeHandle& node = getNodeHandle();
  loop_publisher_ = node.advertise<stereo_fabmap_slam::LoopEdge>("loop_edges", 100);
  map_loaded_publisher_ = node.advertise<stereo_fabmap_slam::MapLoaded>("map_loaded", 1, true);
  mode_publisher_ = node.advertise<std_msgs::String>("mode", 1, true);
  save_service_ = node.advertiseService("save_map", &LoopDetectorNodelet::OnSaveMap, this);
  load_service_ = node.advertiseService("load_map", &LoopDetectorNodelet::OnLoadMap, this);
  mode_service_ = node.advertiseService("set_mode", &LoopDetectorNodelet::OnSetMode, this);
  update_subscriber_ =
      node.subscribe("keyframe_updates", 100, &LoopDetectorNodelet::OnKeyframeUpdate, this);
  {
    stereo_fabmap_slam::SetMode::Request mode_request;
    stereo_fabmap_slam::SetMode::Response mode_response;
    mode_request.mode = private_node.param<std::string>("mode", "mapping");
    OnSetMode(mode_request, mode_response);
    if (!mode_response.success) {
      NODELET_FATAL_STREAM("~mode: " << mode_response.message);
      throw std::runtime_error(mode_response.message);
    }
  }
  const std::string map_file = private_node.param<std::string>("map_file", "");
  if (!map_file.empty()) {
    std::lock_guard<std::mutex> lock(mutex_);
    try {
      NODELET_INFO("map %s loaded: %zu keyframes", map_file.c_str(), LoadMap(map_file));
    } catch (const std::exception& error) {
      NODELET_FATAL_STREAM("~map_file: " << error.what());
      throw;
    }
  }
  detect_service_ = node.advertiseService("detect_loop", &LoopDetectorNodelet::OnDetectLoop, this);
  ros::NodeHandle relocalize_node(node);
  relocalize_node.setCallbackQueue(&relocalize_queue_);
  relocalize_service_ = relocalize_node.advertiseService(
      "relocalize_frame", &LoopDetectorNodelet::OnRelocalizeFrame, this);
  relocalize_spinner_ = std::make_unique<ros::AsyncSpinner>(1, &relocalize_queue_);
  relocalize_spinner_->start();
  graph_subscriber_ = node.subscribe("map_graph", 1, &LoopDetectorNodelet::OnMapGraph, this);
  worker_ = std::thread(&LoopDetectorNodelet::Work, this);
  keyframe_subscriber_ = node.subscribe("keyframes", 100, &LoopDetectorNodelet::OnKeyframe, this);
}

LoopDetectorNodelet::~LoopDetectorNodelet() {
  if (relocalize_spinner_) relocalize_spinner_->stop();
  relocalize_service_.shutdown();  // before its queue
  {
    std::lock_guard<std::mutex> lock(queue_mutex_);
    stopping_ = true;
  }
  wake_.notify_all();
  if (worker_.joinable()) worker_.join();
}

void LoopDetectorNodelet::MakeDetector(const geometry::StereoCamera& camera) {
  if (detector_) return;
  detector_.emplace(pipeline::LoopClosing::LoadDetector(
      place_options_, detector_options_, camera, descriptor_.norm, descriptor_.max_match_distance));
  relocalizer_.emplace(relocalizer_options_, camera, descriptor_.norm,
                       descriptor_.max_match_distance);
  camera_ = camera;
}

place_recognition::LoopDetector& LoopDetectorNodelet::Detector(
    const stereo_fabmap_slam::Keyframe& message) {
  const geometry::StereoCamera camera = ros_conversions::CameraOfKeyframe(message);
  MakeDetector(camera);
  if (camera.size != camera_->size || std::abs(camera.fx - camera_->fx) > 1e-6 * camera_->fx ||
      std::abs(camera.baseline - camera_->baseline) > 1e-6 * camera_->baseline) {
    throw std::invalid_argument(
        "the keyframe's camera differs from the map's (a map of another "
        "camera was loaded?)");
  }
  return *detector_;
}

LoopDetectorNodelet::MapView LoopDetectorNodelet::MakeMapView(
    const std::vector<std::pair<std::int64_t, Eigen::Isometry3d>>& poses,
    const std::vector<std::pair<std::int64_t, std::int64_t>>& joins,
    std::vector<map::SavedEdge> edges, const Eigen::Isometry3d& map_to_odom) const {
  MapView view;
  // Union-find over the joins; each component is named by its smallest id.
  std::map<std::int64_t, std::int64_t> parent;
  const std::function<std::int64_t(std::int64_t)> root = [&](std::int64_t id) {
    while (parent[id] != id) id = parent[id] = parent[parent[id]];
    return id;
  };
  for (const auto& [id, pose] : poses) {
    parent[id] = id;
    view.poses[id] = pose;
  }
  for (const auto& [a, b] : joins) {
    if (parent.count(a) == 0 || parent.count(b) == 0) continue;
    const std::int64_t ra = root(a), rb = root(b);
    if (ra != rb) parent[std::max(ra, rb)] = std::min(ra, rb);
  }
  for (const auto& entry : parent) view.component[entry.first] = root(entry.first);
  if (!view.poses.empty()) view.first = view.poses.begin()->first;
  view.map_to_odom = map_to_odom;
  view.edges = std::move(edges);
  return view;
}

void LoopDetectorNodelet::OnMapGraph(const stereo_fabmap_slam::MapGraphConstPtr& graph) {
  std::vector<std::pair<std::int64_t, Eigen::Isometry3d>> poses;
  for (std::size_t i = 0; i < graph->keyframe_ids.size() && i < graph->keyframe_poses.size(); ++i) {
    poses.emplace_back(static_cast<std::int64_t>(graph->keyframe_ids[i]),
                       ros_conversions::FromPoseMessage(graph->keyframe_poses[i]));
  }
  std::vector<std::pair<std::int64_t, std::int64_t>> joins;
  std::vector<map::SavedEdge> edges;
  for (const stereo_fabmap_slam::MapGraphEdge& edge : graph->edges) {
    const auto a = static_cast<std::int64_t>(edge.from_id),
               b = static_cast<std::int64_t>(edge.to_id);
    joins.emplace_back(a, b);
    if (edge.type == stereo_fabmap_slam::MapGraphEdge::ODOMETRY) continue;
    map::SavedEdge saved;
    saved.edge.match_id = a;
    saved.edge.query_id = b;
    saved.edge.T_match_query = ros_conversions::FromPoseMessage(edge.T_from_to);
    saved.relocalization = edge.type == stereo_fabmap_slam::MapGraphEdge::RELOCALIZATION;
    // Every edge of a kind has the configured uncertainty (loop_detection, relocalization).
    saved.edge.information =
        saved.relocalization
            ? geometry::DiagonalPoseInformation(relocalizer_options_.translation_sigma,
                                                relocalizer_options_.rotation_sigma_deg)
            : geometry::DiagonalPoseInformation(detector_options_.translation_sigma,
                                                detector_options_.rotation_sigma_deg);
    edges.push_back(saved);
  }
  MapView view = MakeMapView(poses, joins, std::move(edges),
                             ros_conversions::FromTransformMessage(graph->map_to_odom));
  std::lock_guard<std::mutex> lock(map_view_mutex_);
  map_view_ = std::move(view);
}

void LoopDetectorNodelet::OnKeyframe(const stereo_fabmap_slam::KeyframeConstPtr& keyframe) {
  {
    std::lock_guard<std::mutex> lock(queue_mutex_);
    queue_.push_back(keyframe);
  }
  wake_.notify_one();
}

void LoopDetectorNodelet::Work() {
  while (true) {
    std::deque<stereo_fabmap_slam::KeyframeConstPtr> waiting;
    {
      std::unique_lock<std::mutex> lock(queue_mutex_);
      wake_.wait(lock, [&] { return stopping_ || !queue_.empty(); });
      if (stopping_) return;
      waiting.swap(queue_);
    }
    for (const stereo_fabmap_slam::KeyframeConstPtr& message : waiting) {
      try {
        std::lock_guard<std::mutex> lock(mutex_);
        if (mode_ == pipeline::SlamMode::kLocalization) continue;  // the map is not extended
        if (static_cast<std::int64_t>(message->id) < loaded_below_) continue;  // before a load
        const bool first_keyframe = !detector_;
        place_recognition::LoopDetector& detector = Detector(*message);
        // A LoopDetector (re)started while the tracker runs: say what its places do not cover.
        if (first_keyframe && message->id > 0 && loaded_below_ == 0) {
          NODELET_WARN(
              "first keyframe received is %lu: the keyframes before it are not places of this "
              "LoopDetector (restarted while the tracker ran?); loops and relocalizations find "
              "keyframes from here on",
              static_cast<unsigned long>(message->id));
        }
        map::Keyframe keyframe = ros_conversions::FromKeyframeMessage(*message);
        keyframe.starts_new_map = keyframe.starts_new_map || next_starts_new_map_;
        next_starts_new_map_ = false;
        const place_recognition::LoopDetection detection = detector.Process(std::move(keyframe));
        if (detection.loop) {
          stereo_fabmap_slam::LoopEdge edge = ros_conversions::ToLoopEdgeMessage(*detection.loop);
          edge.header = message->header;
          loop_publisher_.publish(edge);
          NODELET_INFO("loop: keyframe %ld -> %ld, %d inliers, p = %.2f",
                       static_cast<long>(detection.loop->query_id),
                       static_cast<long>(detection.loop->match_id), detection.loop->inliers,
                       detection.loop->probability);
        }
      } catch (const std::exception& error) {
        NODELET_WARN_THROTTLE(5, "keyframe %lu not detected: %s",
                              static_cast<unsigned long>(message->id), error.what());
      }
    }
  }
}

bool LoopDetectorNodelet::OnDetectLoop(stereo_fabmap_slam::DetectLoop::Request& request,
                                       stereo_fabmap_slam::DetectLoop::Response& response) {
  std::lock_guard<std::mutex> lock(mutex_);
  try {
    place_recognition::LoopDetection detection;
    if (request.keyframe_id >= 0) {
      if (!detector_ || !detector_->database().Contains(request.keyframe_id)) {
        response.message = "keyframe " + std::to_string(request.keyframe_id) + " is not in the map";
        return true;
      }
      detection = detector_->DetectStored(request.keyframe_id);
    } else {
      if (request.keyframe.place_descriptors.empty() || request.keyframe.u.empty()) {
        response.message = "the keyframe has no descriptors";
        return true;
      }
      if (request.add_to_map && detector_ && detector_->database().Contains(request.keyframe.id)) {
        response.message =
            "keyframe " + std::to_string(request.keyframe.id) + " is in the map already";
        return true;
      }
      detection =
          Detector(request.keyframe)
              .Process(ros_conversions::FromKeyframeMessage(request.keyframe), request.add_to_map);
    }
    if (detection.places_compared == 0) {
      response.message = "the map has no place old enough to compare with";
      response.new_place_probability = 1;
      response.success = false;
      return true;
    }
    response.success = true;
    response.new_place_probability = detection.new_place_probability;
    for (const place_recognition::LoopCandidate& candidate : detection.candidates) {
      response.candidate_ids.push_back(static_cast<std::uint64_t>(candidate.keyframe_id));
      response.candidate_probabilities.push_back(candidate.probability);
      response.candidate_inliers.push_back(candidate.inliers);
      response.candidate_accepted.push_back(candidate.accepted);
      response.candidate_reasons.push_back(candidate.reason);
    }
    response.loop_found = detection.loop.has_value();
    if (detection.loop) response.loop = ros_conversions::ToLoopEdgeMessage(*detection.loop);
    response.message = std::to_string(detection.candidates.size()) + " candidates" +
                       (detection.loop ? ", loop found" : ", no loop");
  } catch (const std::exception& error) {
    response.success = false;
    response.message = error.what();
  }
  return true;
}

void LoopDetectorNodelet::OnKeyframeUpdate(
    const stereo_fabmap_slam::KeyframeUpdateConstPtr& message) {
  // The bundle adjustment's poses keep the odometry check of loops and the saved map current.
  std::lock_guard<std::mutex> lock(mutex_);
  if (!detector_) return;
  for (std::size_t i = 0; i < message->keyframe_ids.size() && i < message->keyframe_poses.size();
       ++i) {
    if (static_cast<std::int64_t>(message->keyframe_ids[i]) < loaded_below_) continue;
    detector_->UpdatePose(static_cast<std::int64_t>(message->keyframe_ids[i]),
                          ros_conversions::FromPoseMessage(message->keyframe_poses[i]));
  }
}

std::size_t LoopDetectorNodelet::LoadMap(const std::string& path) {
  const map::SavedMap saved = map::LoadMapFile(path);
  std::optional<place_recognition::LoopDetector> fresh;
  if (!detector_) {
    // No keyframe yet: the map brings its camera; keyframes of another one are refused later.
    fresh.emplace(pipeline::LoopClosing::LoadDetector(place_options_, detector_options_,
                                                      saved.camera, descriptor_.norm,
                                                      descriptor_.max_match_distance));
  }
  const place_recognition::LoopDetector& current = detector_ ? *detector_ : *fresh;
  pipeline::LoopClosing::CheckFits(saved, current, detector_ ? *camera_ : saved.camera);
  place_recognition::LoopDetector restored = pipeline::LoopClosing::RestoreDetector(saved, current);
  // The Backend rebuilds its graph from the same file: a graph that cannot be rebuilt is refused
  // here, before anything changes.
  const backend::PoseGraph graph =
      pipeline::LoopClosing::RestorePoseGraph(saved, pose_graph_options_);
  MakeDetector(saved.camera);
  detector_.emplace(std::move(restored));
  next_starts_new_map_ = true;
  // Until the Backend publishes its rebuilt graph, the view is the saved map's.
  std::vector<std::pair<std::int64_t, Eigen::Isometry3d>> poses;
  std::vector<std::pair<std::int64_t, std::int64_t>> joins;
  for (std::size_t i = 0; i < saved.keyframes.size(); ++i) {
    const map::Keyframe& keyframe = saved.keyframes[i].keyframe;
    poses.emplace_back(keyframe.id, saved.keyframes[i].T_map_camera);
    if (i > 0 && !keyframe.starts_new_map) {
      joins.emplace_back(saved.keyframes[i - 1].keyframe.id, keyframe.id);
    }
  }
  for (const map::SavedEdge& edge : saved.edges) {
    joins.emplace_back(edge.edge.match_id, edge.edge.query_id);
  }
  MapView view = MakeMapView(poses, joins, saved.edges, graph.MapToOdom());
  {
    std::lock_guard<std::mutex> lock(map_view_mutex_);
    map_view_ = std::move(view);
  }
  stereo_fabmap_slam::MapLoaded message;
  message.header.stamp = ros::Time::now();
  message.path = path;
  message.keyframes = saved.keyframes.size();
  for (const map::SavedKeyframe& keyframe : saved.keyframes) {
    message.next_keyframe_id =
        std::max<std::uint64_t>(message.next_keyframe_id, keyframe.keyframe.id + 1);
    for (const std::int64_t point : keyframe.keyframe.map_point_ids) {
      if (point >= 0) {
        message.next_point_id = std::max<std::uint64_t>(message.next_point_id, point + 1);
      }
    }
  }
  loaded_below_ = static_cast<std::int64_t>(message.next_keyframe_id);
  map_loaded_publisher_.publish(message);
  return saved.keyframes.size();
}

bool LoopDetectorNodelet::OnSaveMap(stereo_fabmap_slam::MapFile::Request& request,
                                    stereo_fabmap_slam::MapFile::Response& response) {
  MapView view;
  {
    std::lock_guard<std::mutex> lock(map_view_mutex_);
    view = map_view_;
  }
  std::lock_guard<std::mutex> lock(mutex_);
  if (!detector_ || detector_->database().empty()) {
    response.message = "the map is empty";
    return true;
  }
  try {
    map::SavedMap saved;
    saved.vocabulary_fingerprint = detector_->vocabulary_fingerprint();
    saved.camera = *camera_;
    for (const auto& [id, stored] : detector_->database().keyframes()) {
      const auto pose = view.poses.find(id);
      saved.keyframes.push_back({stored.keyframe, stored.words,
                                 pose != view.poses.end()
                                     ? pose->second
                                     : view.map_to_odom * stored.keyframe.T_world_camera});
    }
    for (const map::SavedEdge& edge : view.edges) {
      if (detector_->database().Contains(edge.edge.match_id) &&
          detector_->database().Contains(edge.edge.query_id)) {
        saved.edges.push_back(edge);
      }
    }
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

bool LoopDetectorNodelet::OnSetMode(stereo_fabmap_slam::SetMode::Request& request,
                                    stereo_fabmap_slam::SetMode::Response& response) {
  std::lock_guard<std::mutex> lock(mutex_);
  for (const auto& entry : pipeline::kSlamModeNames) {
    if (request.mode == entry.name) {
      if (mode_ == pipeline::SlamMode::kLocalization &&
          entry.value == pipeline::SlamMode::kMapping) {
        next_starts_new_map_ = true;
      }
      mode_ = entry.value;
      std_msgs::String message;
      message.data = entry.name;
      mode_publisher_.publish(message);
      response.success = true;
      response.message = "mode " + request.mode;
      NODELET_INFO("mode %s", entry.name);
      return true;
    }
  }
  response.message = "unknown mode '" + request.mode + "' (mapping, localization)";
  return true;
}

bool LoopDetectorNodelet::OnRelocalizeFrame(
    stereo_fabmap_slam::RelocalizeFrame::Request& request,
    stereo_fabmap_slam::RelocalizeFrame::Response& response) {
  const auto start = std::chrono::steady_clock::now();
  MapView view;
  {
    std::lock_guard<std::mutex> lock(map_view_mutex_);
    view = map_view_;
  }
  std::lock_guard<std::mutex> lock(mutex_);
  try {
    if (!detector_ || detector_->database().empty()) {
      response.status = "empty map";
      response.message = "the map is empty";
      return true;
    }
    const bool recover = request.mode == stereo_fabmap_slam::RelocalizeFrame::Request::RECOVER;
    if (recover && view.InMap(request.reference_keyframe_id)) {
      response.already_joined = true;
      response.status = "success";
      response.message = "the frame's piece of odometry is in the map already";
      return true;
    }
    const map::Keyframe frame = ros_conversions::FromKeyframeMessage(request.frame);
    const relocalization::Relocalization result =
        relocalizer_->Relocalize(frame.features, detector_->Words(frame.place_descriptors),
                                 *detector_, [&](const map::StoredKeyframe& keyframe) {
                                   return !recover || view.InMap(keyframe.keyframe.id);
                                 });
    response.success = result.success();
    response.status = relocalization::RelocalizationStatusName(result.status);
    response.message = result.reason;
    response.matches = result.matches;
    response.inliers = result.inliers;
    response.probability = result.probability;
    if (result.success()) {
      response.keyframe_id = static_cast<std::uint64_t>(result.keyframe_id);
      response.T_keyframe_camera = ros_conversions::ToPoseMessage(result.T_keyframe_camera);
      // The keyframe's map pose from the latest map_graph; a keyframe too new to be in it yet
      // (the Backend publishes after adjusting it) is placed by its odometry and map -> odom.
      const auto pose = view.poses.find(result.keyframe_id);
      const Eigen::Isometry3d T_map_keyframe =
          pose != view.poses.end()
              ? pose->second
              : view.map_to_odom *
                    detector_->database().Get(result.keyframe_id).keyframe.T_world_camera;
      response.map_pose_known = pose != view.poses.end() || view.first >= 0;
      response.T_map_camera =
          ros_conversions::ToPoseMessage(T_map_keyframe * result.T_keyframe_camera);
      if (request.add_edge && request.reference_keyframe_id >= 0 &&
          request.reference_keyframe_id != result.keyframe_id) {
        map::LoopEdge edge;
        edge.match_id = result.keyframe_id;
        edge.query_id = request.reference_keyframe_id;
        edge.T_match_query = result.T_keyframe_camera *
                             ros_conversions::FromPoseMessage(request.T_reference_camera).inverse();
        edge.information = geometry::DiagonalPoseInformation(
            relocalizer_options_.translation_sigma, relocalizer_options_.rotation_sigma_deg);
        edge.inliers = result.inliers;
        edge.probability = result.probability;
        stereo_fabmap_slam::LoopEdge message = ros_conversions::ToLoopEdgeMessage(edge);
        message.header = request.frame.header;
        message.relocalization = true;
        loop_publisher_.publish(message);
        response.edge_added = true;
        NODELET_INFO("relocalized: keyframe %ld joined to %ld, %d inliers",
                     static_cast<long>(edge.query_id), static_cast<long>(edge.match_id),
                     result.inliers);
      }
    }
  } catch (const std::exception& error) {
    response.success = false;
    response.status = "error";
    response.message = error.what();
  }
  response.time_ms =
      std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
  return true;
}

}  // namespace stereo_fabmap_slam

PLUGINLIB_EXPORT_CLASS(stereo_fabmap_slam::LoopDetectorNodelet, nodelet::Nodelet)
