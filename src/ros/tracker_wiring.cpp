#include "tracker_wiring.h"

#include <chrono>
#include <cmath>
#include <stdexcept>

#include <cv_bridge/cv_bridge.h>
#include <ros/console.h>
#include <stereo_fabmap_slam/RelocalizeFrame.h>

#include "parameter_reader.h"
#include "ros_conversions.h"
#include "stage_conversions.h"
#include "stereo_fabmap_slam/place_recognition/place_recognition_options.h"
#include "stereo_image_input.h"

namespace stereo_fabmap_slam::ros_wiring {

double WallSeconds() {
  return std::chrono::duration<double>(std::chrono::system_clock::now().time_since_epoch()).count();
}

double SteadyMilliseconds() {
  return std::chrono::duration<double, std::milli>(
             std::chrono::steady_clock::now().time_since_epoch())
      .count();
}

TrackerParameters ReadTrackerParameters(const ros::NodeHandle& private_node) {
  // A configuration file first (config/euroc.yaml and its presets), then single private
  // parameters "~<section>/<key>" on top; a bad value stops start-up with its name.
  TrackerParameters p;
  p.rectification = ros_parameters::ReadModuleOptions(private_node, p.rectification);
  p.printed += ros_parameters::PrintedOptions(p.rectification);
  p.options.ForEachModule([&](auto& options) {
    options = ros_parameters::ReadModuleOptions(private_node, options);
    p.printed += ros_parameters::PrintedOptions(options);
  });
  p.relocalizer = ros_parameters::ReadModuleOptions(private_node, p.relocalizer);
  p.printed += ros_parameters::PrintedOptions(p.relocalizer);
  p.loop_closing = private_node.param("loop_closing", true);
  // Loop closing needs place descriptors in every keyframe, with place recognition's own key
  // point selection (config/fabmap.yaml).
  if (p.loop_closing) {
    std::string fabmap_config;
    if (!private_node.getParam("fabmap_config", fabmap_config)) {
      throw std::invalid_argument(
          "set ~fabmap_config (e.g. config/fabmap.yaml) or ~loop_closing false");
    }
    p.options.place_features =
        place_recognition::LoadPlaceRecognitionOptions(fabmap_config, p.options.features).features;
    p.printed += "place recognition features from " + fabmap_config + "\n";
  }
  // REP-105 names, as rtabmap_ros and slam_toolbox default to.
  p.frames.odom = private_node.param<std::string>("odom_frame", p.frames.odom);
  p.frames.base = private_node.param<std::string>("base_frame", p.frames.base);
  p.frames.camera = private_node.param<std::string>("camera_frame", p.frames.camera);
  p.frames.map = private_node.param<std::string>("map_frame", p.frames.map);
  p.publish_tf = private_node.param("publish_tf", p.publish_tf);
  p.use_camera_info = private_node.param("use_camera_info", p.use_camera_info);
  p.approximate_sync = private_node.param("approximate_sync", p.approximate_sync);
  p.lockstep = private_node.param("lockstep", p.lockstep);
  p.queue_size = private_node.param("queue_size", p.queue_size);
  if (p.queue_size < 1) throw std::invalid_argument("~queue_size must be >= 1");
  p.monitor.max_prediction_gap = p.options.tracker.max_prediction_gap;
  p.monitor.unpaired_limit = p.queue_size;
  p.base_to_camera = ros_input::ReadBaseToCamera(private_node);
  if (p.use_camera_info && !p.base_to_camera) {
    p.warnings.push_back(
        "use_camera_info without ~base_to_camera: camera_info does not say where the camera "
        "sits, so base_link is taken to be the raw left camera (z forward, not REP-103's x "
        "forward, z up); give ~base_to_camera for a robot's base");
  }
  if (!p.use_camera_info && !private_node.getParam("calibration_file", p.calibration_file)) {
    throw std::invalid_argument(
        "set ~calibration_file (e.g. config/euroc_stereo.yaml) or ~use_camera_info");
  }
  // The map's parameters are the LoopDetector's; without it (loop_closing false) they would be
  // dropped without a word, and the user would believe the map saved or used.
  if (!p.loop_closing && (!private_node.param<std::string>("map_file", "").empty() ||
                          !private_node.param<std::string>("save_map", "").empty() ||
                          private_node.param<std::string>("mode", "mapping") != "mapping")) {
    throw std::invalid_argument(
        "~map_file, ~save_map and ~mode localization need loop closing (the LoopDetector keeps "
        "the map): set loop_closing true or leave them out");
  }
  ros_parameters::RejectUnknownParameters(
      private_node, {"approximate_sync", "base_frame", "base_to_camera", "calibration_file",
                     "camera_frame", "config_file", "fabmap_config", "image_transport", "lockstep",
                     "loop_closing", "map_file", "map_frame", "mode", "odom_frame", "publish_tf",
                     "queue_size", "save_map", "use_camera_info"});
  return p;
}

std::string ImageRefusal(const sensor_msgs::Image& left, const sensor_msgs::Image& right) {
  for (const sensor_msgs::Image* image : {&left, &right}) {
    const std::string problem = ros_conversions::MalformedImageReason(*image);
    if (!problem.empty()) {
      return std::string("malformed image on ") + (image == &left ? "left" : "right") +
             "/image_raw: " + problem;
    }
  }
  return "";
}

std::optional<pipeline::StereoPair> StereoPairOf(const ImagePair& pair, std::string* refusal) {
  *refusal = ImageRefusal(*pair.left, *pair.right);
  if (!refusal->empty()) return std::nullopt;
  try {
    return pipeline::StereoPair{ros_conversions::ToSeconds(pair.left->header.stamp),
                                cv_bridge::toCvShare(pair.left, "mono8")->image,
                                cv_bridge::toCvShare(pair.right, "mono8")->image, pair.arrival};
  } catch (const cv_bridge::Exception& error) {
    *refusal = "unsupported image encoding (" + pair.left->encoding + " / " + pair.right->encoding +
               "): " + error.what();
    return std::nullopt;
  }
}

RelocalizeFrameClient::RelocalizeFrameClient(const ros::NodeHandle& node, std::string odom_frame)
    : node_(node), odom_frame_(std::move(odom_frame)) {}

std::optional<pipeline::RelocalizationAnswer> RelocalizeFrameClient::Call(
    const pipeline::RelocalizationRequest& request, const geometry::StereoCamera& camera,
    const ros::Time& stamp) {
  stereo_fabmap_slam::RelocalizeFrame call;
  call.request = ros_conversions::ToRelocalizeFrameRequest(request, camera, odom_frame_);
  call.request.frame.header.stamp = stamp;
  if (!client_.isValid()) {
    client_ = node_.serviceClient<stereo_fabmap_slam::RelocalizeFrame>("relocalize_frame", true);
  }
  if (!client_.call(call)) return std::nullopt;
  return ros_conversions::FromRelocalizeFrameResponse(call.response);
}

void EventLog::Log(const pipeline::InputEvent& event) {
  if (event.repeats) {
    std::lock_guard<std::mutex> lock(mutex_);
    const double now = WallSeconds();
    const auto key =
        std::make_pair(event.kind, event.message.substr(0, event.message.find_first_of(":(")));
    const auto it = last_logged_.find(key);
    if (it != last_logged_.end() && now - it->second < 2.0) return;
    last_logged_[key] = now;
  }
  if (event.warning) {
    ROS_WARN("[%s] %s", name_.c_str(), event.message.c_str());
  } else {
    ROS_INFO("[%s] %s", name_.c_str(), event.message.c_str());
  }
}

void TrackingNews::Report(const odometry::TrackingResult& result, EventLog* log) {
  if (result.state == odometry::TrackingState::kLost) {
    const bool new_segment = result.keyframe && result.keyframe->starts_new_segment;
    log->Log({pipeline::InputEvent::Kind::kTrackingLost, "tracking lost: " + result.reason, true,
              !new_segment});
    lost_with_map_kept_ = result.map_kept ? lost_with_map_kept_ + 1 : 0;
  } else if (lost_with_map_kept_ > 0) {
    log->Log({pipeline::InputEvent::Kind::kTrackingFound,
              "tracking found the map again after " + std::to_string(lost_with_map_kept_) +
                  " lost frame(s); odom goes on unbroken",
              false, false});
    lost_with_map_kept_ = 0;
  }
}

void PairQueue::Configure(std::size_t capacity, double catch_up_gap,
                          pipeline::InputMonitor* monitor) {
  std::lock_guard<std::mutex> lock(mutex_);
  queue_.emplace(capacity, catch_up_gap);
  monitor_ = monitor;
}

std::vector<pipeline::InputEvent> PairQueue::Push(const sensor_msgs::ImageConstPtr& left,
                                                  const sensor_msgs::ImageConstPtr& right) {
  std::vector<pipeline::InputEvent> events;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    const std::uint64_t arrival = ++arrivals_;
    events = monitor_->OnPair(WallSeconds());
    // A full queue drops the newest pair: what waits stays a contiguous stretch of the stream.
    if (!queue_->Push(left->header.stamp.toSec(), ImagePair{left, right, arrival})) {
      monitor_->CountSkipped(1);
    }
    if (auto report = monitor_->SkipReport(WallSeconds(), last_frame_ms_)) {
      events.push_back(*report);
    }
  }
  ready_.notify_one();
  return events;
}

std::optional<ImagePair> PairQueue::Take(std::vector<pipeline::InputEvent>* events) {
  std::unique_lock<std::mutex> lock(mutex_);
  while (!stopping_ && queue_->empty()) {
    // Idle with skips not yet reported (the stream ended or paused): report them when their
    // second is up rather than never.
    if (!monitor_->HasUnreportedSkips()) {
      ready_.wait(lock);
      continue;
    }
    const double wait = monitor_->NextSkipReport() - WallSeconds();
    if (wait > 0) ready_.wait_for(lock, std::chrono::duration<double>(wait));
    if (auto report = monitor_->SkipReport(WallSeconds(), last_frame_ms_)) {
      events->push_back(*report);
    }
  }
  if (stopping_) return std::nullopt;
  odometry::FrameQueue<ImagePair>::Taken taken = queue_->Take();
  monitor_->CountSkipped(taken.skipped);
  return std::move(taken.frame);
}

void PairQueue::FrameDone(double milliseconds) {
  std::lock_guard<std::mutex> lock(mutex_);
  last_frame_ms_ = milliseconds;
}

void PairQueue::Stop() {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    stopping_ = true;
  }
  ready_.notify_all();
}

void MappingProgress::OnGraph(const stereo_fabmap_slam::MapGraph& graph) {
  auto snapshot =
      std::make_shared<pipeline::MapSnapshot>(ros_conversions::FromMapGraphMessage(graph));
  {
    std::lock_guard<std::mutex> lock(mutex_);
    snapshot_ = std::move(snapshot);
    last_closed_ = std::max(last_closed_, graph.last_closed_keyframe_id);
    relocalization_edges_ =
        std::max<std::uint64_t>(relocalization_edges_, graph.relocalization_edges_received);
  }
  changed_.notify_all();
}

void MappingProgress::OnUpdate(std::int64_t keyframe_id) {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    last_update_ = std::max(last_update_, keyframe_id);
  }
  changed_.notify_all();
}

std::shared_ptr<const pipeline::MapSnapshot> MappingProgress::Snapshot() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return snapshot_;
}

void MappingProgress::OnRelocalizationEdgeSent() {
  std::lock_guard<std::mutex> lock(mutex_);
  ++relocalization_edges_sent_;
}

bool MappingProgress::WaitFor(std::int64_t keyframe, bool loop_closing, double timeout) {
  std::unique_lock<std::mutex> lock(mutex_);
  return changed_.wait_for(lock, std::chrono::duration<double>(timeout), [&] {
    return last_update_ >= keyframe && (!loop_closing || last_closed_ >= keyframe) &&
           relocalization_edges_ >= relocalization_edges_sent_;
  });
}

}  // namespace stereo_fabmap_slam::ros_wiring
