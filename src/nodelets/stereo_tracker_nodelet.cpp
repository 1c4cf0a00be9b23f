// StereoTracker: the tracking stage (pipeline::TrackingStage) in the nodelet graph. Stereo pairs
// in; odometry, tf odom -> base_link (and the camera's mounting), keyframes and tracked_frames
// out; the relocalize service. The stage decides; this file wires: parameters, subscriptions, a
// bounded queue and a worker thread, conversions, the relocalize_frame call to the LoopDetector,
// and in lockstep mode the wait for the other stages.
#include <memory>
#include <mutex>
#include <optional>
#include <thread>

#include <nodelet/nodelet.h>
#include <ros/callback_queue.h>
#include <ros/ros.h>
#include <std_msgs/String.h>
#include <stereo_fabmap_slam/MapLoaded.h>
#include <stereo_fabmap_slam/Relocalize.h>
#include <pluginlib/class_list_macros.hpp>

#include "ros_conversions.h"
#include "stage_conversions.h"
#include "stereo_fabmap_slam/pipeline/tracking_stage.h"
#include "stereo_image_input.h"
#include "tracker_outputs.h"
#include "tracker_wiring.h"

namespace stereo_fabmap_slam {

class StereoTrackerNodelet : public nodelet::Nodelet {
 public:
  ~StereoTrackerNodelet() override {
    input_.reset();               // no image callback runs on after this (StereoImageInput)
    relocalize_service_.reset();  // before the stage its calls reach
    pairs_.Stop();
    if (worker_.joinable()) worker_.join();
  }

 private:
  void onInit() override;
  void Subscribe(ros::NodeHandle& node);
  void Calibrate(const ros_input::MountedRig& rig);  // once; call with mutex_
  void Work();
  void ProcessPair(const ros_wiring::ImagePair& pair);
  // Asks the LoopDetector (relocalize_frame), hands the answer to the stage and returns it (none:
  // the service could not be called). Call with mutex_.
  std::optional<pipeline::RelocalizationAnswer> Relocalize(
      const ros::Time& stamp, const pipeline::RelocalizationRequest& request);
  // The relocalize service's answer, handed over without the stage's lock.
  void AnswerUser(const pipeline::UserRelocalization& answer) {
    if (relocalize_service_) relocalize_service_->Answer(answer);
  }
  void Log(const pipeline::InputEvent& event) { event_log_.Log(event); }

  ros_wiring::TrackerParameters parameters_;
  ros_wiring::EventLog event_log_{"stereo_tracker"};
  ros_wiring::TrackingNews news_;  // worker only
  std::unique_ptr<ros_wiring::TrackerOutputs> outputs_;
  std::mutex mutex_;  // the stage: the worker, the update, mode and map callbacks share it
  std::unique_ptr<pipeline::TrackingStage> stage_;  // calibrated at start or by camera_info
  ros_wiring::PairQueue pairs_;
  ros_wiring::MappingProgress mapping_;  // map_graph, updates: the snapshot and lockstep's cue
  std::thread worker_;
  std::unique_ptr<ros_input::StereoImageInput> input_;
  ros::Subscriber update_subscriber_, graph_subscriber_, mode_subscriber_, loaded_subscriber_;
  std::optional<ros_wiring::RelocalizeFrameClient> relocalize_frame_;  // with loop closing
  std::unique_ptr<ros_wiring::RelocalizeService> relocalize_service_;
};

void StereoTrackerNodelet::onInit() {
  ros::NodeHandle& node = getNodeHandle();
  try {  // everything that can refuse, before any ROS object exists (a throw unloads cleanly)
    parameters_ = ros_wiring::ReadTrackerParameters(getPrivateNodeHandle());
  } catch (const std::exception& error) {
    NODELET_FATAL_STREAM("bad configuration: " << error.what());
    throw;
  }
  const ros_wiring::TrackerParameters& p = parameters_;
  NODELET_INFO_STREAM("options in force:\n" << p.printed);
  for (const std::string& warning : p.warnings) NODELET_WARN("%s", warning.c_str());
  stage_ = std::make_unique<pipeline::TrackingStage>(p.options, p.monitor, p.relocalizer,
                                                     ros_wiring::SteadyMilliseconds);
  pairs_.Configure(p.options.tracker.queued_pairs, p.options.tracker.catch_up_gap,
                   &stage_->input());
  outputs_ = std::make_unique<ros_wiring::TrackerOutputs>(node, p.frames, p.publish_tf);
  Subscribe(node);
  if (!p.use_camera_info) {
    std::lock_guard<std::mutex> lock(mutex_);
    try {
      Calibrate(
          ros_input::RigFromCalibrationFile(p.calibration_file, p.rectification, p.base_to_camera));
    } catch (const std::exception& error) {
      NODELET_FATAL_STREAM("calibration: " << error.what());
      throw;
    }
  }
  input_ = std::make_unique<ros_input::StereoImageInput>(
      node, getPrivateNodeHandle(), p.queue_size, p.approximate_sync,
      [this](const auto& left, const auto& right) {
        for (const pipeline::InputEvent& event : pairs_.Push(left, right)) Log(event);
      },
      [this](int side) {
        for (const auto& event : stage_->input().OnImage(side, ros_wiring::WallSeconds())) {
          Log(event);
        }
      });
  if (p.use_camera_info) {
    input_->SubscribeCameraInfo(node, p.queue_size, [this](const auto& left, const auto& right) {
      std::lock_guard<std::mutex> lock(mutex_);
      if (stage_->calibrated()) return;  // the first pair defines the rectification
      try {
        Calibrate(ros_input::RigFromCameraInfo(*left, *right, parameters_.base_to_camera));
      } catch (const std::exception& error) {
        NODELET_WARN_THROTTLE(5, "camera_info pair unusable: %s", error.what());
      }
    });
  }
  worker_ = std::thread(&StereoTrackerNodelet::Work, this);
  NODELET_INFO_STREAM("tracking " << input_->Describe() << (p.lockstep ? ", lockstep" : ""));
}

void StereoTrackerNodelet::Subscribe(ros::NodeHandle& node) {
  update_subscriber_ = node.subscribe<stereo_fabmap_slam::KeyframeUpdate>(
      "keyframe_updates", 100, [this](const stereo_fabmap_slam::KeyframeUpdateConstPtr& m) {
        const pipeline::MappedKeyframe mapped = ros_conversions::FromMappedKeyframeMessage(*m);
        {
          std::lock_guard<std::mutex> lock(mutex_);
          stage_->ApplyUpdate(mapped.update);
        }
        mapping_.OnUpdate(mapped.keyframe_id);
      });
  if (!parameters_.loop_closing) return;
  graph_subscriber_ = node.subscribe<stereo_fabmap_slam::MapGraph>(
      "map_graph", 1,
      [this](const stereo_fabmap_slam::MapGraphConstPtr& m) { mapping_.OnGraph(*m); });
  mode_subscriber_ =
      node.subscribe<std_msgs::String>("mode", 1, [this](const std_msgs::StringConstPtr& m) {
        const std::optional<pipeline::SlamMode> mode = pipeline::ParseSlamMode(m->data);
        std::lock_guard<std::mutex> lock(mutex_);
        if (mode) stage_->SetMode(*mode, !mapping_.Snapshot()->empty());
      });
  loaded_subscriber_ = node.subscribe<stereo_fabmap_slam::MapLoaded>(
      "map_loaded", 1, [this](const stereo_fabmap_slam::MapLoadedConstPtr& m) {
        const pipeline::LoadedMap loaded{m->keyframes,
                                         static_cast<std::int64_t>(m->next_keyframe_id),
                                         static_cast<std::int64_t>(m->next_point_id)};
        std::lock_guard<std::mutex> lock(mutex_);
        stage_->OnMapLoaded(loaded);
      });
  relocalize_frame_.emplace(node, parameters_.frames.odom);
  relocalize_service_ = std::make_unique<ros_wiring::RelocalizeService>(
      node, *outputs_,
      ros_wiring::RelocalizeService::Hooks{[this] { return mapping_.Snapshot()->empty(); },
                                           [this](bool reanchor) {
                                             std::lock_guard<std::mutex> lock(mutex_);
                                             stage_->RequestRelocalization(reanchor);
                                           },
                                           [this] {
                                             std::lock_guard<std::mutex> lock(mutex_);
                                             stage_->CancelRelocalizationRequest();
                                           }});
}

void StereoTrackerNodelet::Calibrate(const ros_input::MountedRig& rig) {
  // odom is the base at the first frame (REP-105): the camera starts at its mounting, and every
  // pose the stages exchange is in odom.
  stage_->Calibrate(rig.rectifier, rig.T_base_camera);
  outputs_->SetMounting(rig.T_base_camera);
  NODELET_INFO("stereo camera: baseline %.3f m, %dx%d", stage_->camera().baseline,
               stage_->camera().size.width, stage_->camera().size.height);
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
  pipeline::TrackingOutput output;
  try {
    std::string refusal;
    const std::optional<pipeline::StereoPair> stereo = ros_wiring::StereoPairOf(pair, &refusal);
    output = stereo ? stage_->Process(*stereo, mapping_.Snapshot().get()) : stage_->Refuse(refusal);
  } catch (const std::exception& error) {
    output = stage_->Refuse(std::string("tracking failed: ") + error.what());
  }
  for (const pipeline::InputEvent& event : output.events) Log(event);
  if (!output.tracked) {  // said on tracked_frames too: every pair taken gets its message
    outputs_->PublishFrame(stamp, ros_conversions::RefusedFrameMessage(
                                      seconds, stage_->input().counts(), parameters_.frames.odom));
    return;
  }
  news_.Report(output.tracking, &event_log_);
  outputs_->PublishTracking(stamp, output, stage_->camera(),
                            stage_->front_end().last_rectified_left());
  const std::optional<pipeline::RelocalizationAnswer> answer =
      output.relocalization ? Relocalize(stamp, *output.relocalization) : std::nullopt;
  const pipeline::FrameRecord record =
      stage_->RecordFrame(output, seconds, answer ? &*answer : nullptr);
  const pipeline::InputCounts counts = stage_->input().counts();
  lock.unlock();
  if (output.user) AnswerUser(*output.user);  // a frame without a pose: why
  // Lockstep: the other stages' answers before the next pair, in the order run_dataset takes
  // them.
  const std::int64_t keyframe = output.tracking.keyframe ? output.tracking.keyframe->id : -1;
  if (parameters_.lockstep &&
      !mapping_.WaitFor(keyframe, parameters_.loop_closing, parameters_.lockstep_timeout)) {
    NODELET_WARN(
        "lockstep: no answer from the Backend or LoopDetector within %.0f s for the "
        "pair at %.3f; going on",
        parameters_.lockstep_timeout, seconds);
  }
  outputs_->PublishFrame(
      stamp, ros_conversions::ToTrackedFrameMessage(record, counts, parameters_.frames.odom));
}

std::optional<pipeline::RelocalizationAnswer> StereoTrackerNodelet::Relocalize(
    const ros::Time& stamp, const pipeline::RelocalizationRequest& request) {
  const std::optional<pipeline::RelocalizationAnswer> answer =
      relocalize_frame_ ? relocalize_frame_->Call(request, stage_->camera(), stamp) : std::nullopt;
  if (!answer) {
    const std::string reason = "the LoopDetector's relocalize_frame service is not available";
    NODELET_WARN_THROTTLE(5, "relocalization: %s", reason.c_str());
    const pipeline::RelocalizationOutcome outcome = stage_->OnNoRelocalization(request, reason);
    if (outcome.user) AnswerUser(*outcome.user);
    return std::nullopt;
  }
  if (answer->edge) mapping_.OnRelocalizationEdgeSent();
  const pipeline::RelocalizationOutcome outcome = stage_->OnRelocalization(request, *answer);
  if (!outcome.news.empty()) NODELET_INFO("%s", outcome.news.c_str());
  if (outcome.T_map_odom) outputs_->PublishCorrection(stamp, *outcome.T_map_odom);
  if (outcome.user) AnswerUser(*outcome.user);
  return answer;
}

}  // namespace stereo_fabmap_slam

PLUGINLIB_EXPORT_CLASS(stereo_fabmap_slam::StereoTrackerNodelet, nodelet::Nodelet)
