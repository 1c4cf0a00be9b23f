#pragma once

// The StereoTracker nodelet's plumbing, apart from the nodelet so that it stays wiring only and
// this is unit-tested: its parameters, the bounded queue between the image callbacks and the
// tracking thread, the relocalize service's wait for a frame, what the other stages have
// answered (map_graph, keyframe_updates: the map's snapshot and lockstep's cue), and the log of
// the input monitor's events. None of it decides anything about tracking: that is the stage's.

#include <condition_variable>
#include <cstdint>
#include <functional>
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include <ros/node_handle.h>
#include <ros/service_client.h>
#include <sensor_msgs/Image.h>
#include <stereo_fabmap_slam/MapGraph.h>
#include <Eigen/Geometry>

#include "stereo_fabmap_slam/camera/camera_options.h"
#include "stereo_fabmap_slam/geometry/stereo_camera.h"
#include "stereo_fabmap_slam/odometry/frame_queue.h"
#include "stereo_fabmap_slam/pipeline/input_monitor.h"
#include "stereo_fabmap_slam/pipeline/map_state.h"
#include "stereo_fabmap_slam/pipeline/relocalization_policy.h"
#include "stereo_fabmap_slam/pipeline/stereo_front_end.h"
#include "stereo_fabmap_slam/pipeline/tracking_stage.h"
#include "stereo_fabmap_slam/relocalization/relocalization_options.h"
#include "tracker_outputs.h"

namespace stereo_fabmap_slam::ros_wiring {

double WallSeconds();
double SteadyMilliseconds();

struct TrackerParameters {
  camera::RectificationOptions rectification;
  pipeline::FrontEndOptions options;
  relocalization::RelocalizerOptions relocalizer;
  pipeline::InputMonitorOptions monitor;
  FrameNames frames;
  bool publish_tf = true;
  bool use_camera_info = false;
  bool approximate_sync = false;
  bool loop_closing = true;
  // Each pair waits for the other stages' answers to it (its keyframe's bundle adjustment and
  // loop detection, its relocalization edge) before tracked_frames says it is done.
  bool lockstep = false;
  double lockstep_timeout = 30.0;  // [s] a stage that does not answer is not waited for longer
  std::optional<Eigen::Isometry3d> base_to_camera;
  std::string calibration_file;
  int queue_size = 10;
  std::string printed;                // the options in force, for the start-up log
  std::vector<std::string> warnings;  // what the user should hear about the configuration
};
// Every ~parameter of the StereoTracker; throws std::exception naming a bad or missing one.
TrackerParameters ReadTrackerParameters(const ros::NodeHandle& private_node);

// Logs the input monitor's events: warnings and news, a repeating one at most every 2 s (each
// kind of each fault on its own clock: its message up to the first ':' or '('). `name`: the
// nodelet's, to prefix the lines.
class EventLog {
 public:
  explicit EventLog(std::string name) : name_(std::move(name)) {}
  void Log(const pipeline::InputEvent& event);

 private:
  std::string name_;
  std::mutex mutex_;
  std::map<std::pair<pipeline::InputEvent::Kind, std::string>, double> last_logged_;
};

// Why a pair of image messages cannot be read ("" if it can): a message that is not what it says
// (ros_conversions::MalformedImageReason), named with its side.
std::string ImageRefusal(const sensor_msgs::Image& left, const sensor_msgs::Image& right);

// Says what the tracker's results mean for the user: "tracking lost" (once for each new
// segment, never throttled, so that they can be counted; throttled while the tracker searches
// its map), and "tracking found the map again" after frames lost with the map kept.
class TrackingNews {
 public:
  void Report(const odometry::TrackingResult& result, EventLog* log);

 private:
  int lost_with_map_kept_ = 0;
};

struct ImagePair {
  sensor_msgs::ImageConstPtr left, right;
  std::uint64_t arrival = 0;  // its place in the stream of pairs (1, 2, ...)
};

// The pair as the tracking stage takes it: mono8 images (colour converted, shared where they are
// mono8 already). nullopt with `refusal` saying why for messages that are no images (checked
// before any pixel is read: ImageRefusal) or encodings cv_bridge cannot convert.
std::optional<pipeline::StereoPair> StereoPairOf(const ImagePair& pair, std::string* refusal);

// The StereoTracker's calls of the LoopDetector's relocalize_frame: a persistent connection,
// made again after the LoopDetector restarted.
class RelocalizeFrameClient {
 public:
  RelocalizeFrameClient(const ros::NodeHandle& node, std::string odom_frame);
  // The place stage's answer to `request` about the frame at `stamp`; nullopt when no
  // LoopDetector answers.
  std::optional<pipeline::RelocalizationAnswer> Call(const pipeline::RelocalizationRequest& request,
                                                     const geometry::StereoCamera& camera,
                                                     const ros::Time& stamp);

 private:
  ros::NodeHandle node_;
  std::string odom_frame_;
  ros::ServiceClient client_;
};

// Between the synchroniser and the tracking thread: a bounded odometry::FrameQueue, so that a
// tracker slower than the camera skips whole pairs instead of falling behind and the subscribers'
// queues never overflow (which would drop a left image without its right). Pairs dropped from a
// full queue or passed over count as skipped in the input monitor, which reports them once a
// second, also while the stream pauses.
class PairQueue {
 public:
  // `monitor`: the tracking stage's, which counts every pair (it outlives the queue's use).
  void Configure(std::size_t capacity, double catch_up_gap, pipeline::InputMonitor* monitor);
  // From the synchroniser. Returns the monitor's events (a dropout's end, skip reports).
  std::vector<pipeline::InputEvent> Push(const sensor_msgs::ImageConstPtr& left,
                                         const sensor_msgs::ImageConstPtr& right);
  // Waits for the next pair to track; nullopt when stopping. `events` receives skip reports.
  std::optional<ImagePair> Take(std::vector<pipeline::InputEvent>* events);
  void FrameDone(double milliseconds);  // the tracker's time for its last pair, for the reports
  void Stop();

 private:
  std::mutex mutex_;
  std::condition_variable ready_;
  std::optional<odometry::FrameQueue<ImagePair>> queue_;
  pipeline::InputMonitor* monitor_ = nullptr;
  std::uint64_t arrivals_ = 0;
  double last_frame_ms_ = 0;
  bool stopping_ = false;
};

// What the mapping stage (the Backend) has answered, from its map_graph and keyframe_updates:
// the map's snapshot for the tracking stage, and in lockstep mode the cue to go on.
class MappingProgress {
 public:
  void OnGraph(const stereo_fabmap_slam::MapGraph& graph);
  void OnUpdate(std::int64_t keyframe_id);
  std::shared_ptr<const pipeline::MapSnapshot> Snapshot() const;
  // The LoopDetector answered a relocalization with an edge, which it sent to the Backend.
  void OnRelocalizationEdgeSent();
  // Waits until the Backend has answered keyframe `keyframe` (-1: none) with its update and, if
  // `loop_closing`, applied its loop detection, and has received every relocalization edge sent;
  // false after `timeout` seconds without.
  bool WaitFor(std::int64_t keyframe, bool loop_closing, double timeout);

 private:
  mutable std::mutex mutex_;
  std::condition_variable changed_;
  std::shared_ptr<const pipeline::MapSnapshot> snapshot_ =
      std::make_shared<pipeline::MapSnapshot>();
  std::int64_t last_update_ = -1, last_closed_ = -1;
  std::uint64_t relocalization_edges_ = 0;  // the Backend has received
  std::uint64_t relocalization_edges_sent_ = 0;
};

}  // namespace stereo_fabmap_slam::ros_wiring
