// LoopDetector: keyframes in, verified loop edges out, and the detect_loop service. Everything
// algorithmic is place_recognition::LoopDetector; this file converts, queues and publishes.
#include <condition_variable>
#include <deque>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <thread>

#include <nodelet/nodelet.h>
#include <ros/ros.h>
#include <stereo_fabmap_slam/DetectLoop.h>
#include <pluginlib/class_list_macros.hpp>

#include "parameter_reader.h"
#include "ros_conversions.h"
#include "stereo_fabmap_slam/features/feature_factory.h"
#include "stereo_fabmap_slam/pipeline/loop_closing.h"

namespace stereo_fabmap_slam {

class LoopDetectorNodelet : public nodelet::Nodelet {
 public:
  ~LoopDetectorNodelet() override;

 private:
  void onInit() override;
  void OnKeyframe(const stereo_fabmap_slam::KeyframeConstPtr& keyframe);
  bool OnDetectLoop(stereo_fabmap_slam::DetectLoop::Request& request,
                    stereo_fabmap_slam::DetectLoop::Response& response);
  void Work();
  // The detector needs the camera, which arrives with the first keyframe. Call with mutex_.
  place_recognition::LoopDetector& Detector(const stereo_fabmap_slam::Keyframe& message);

  place_recognition::PlaceRecognitionOptions place_options_;
  place_recognition::LoopDetectorOptions detector_options_;
  features::DescriptorKind descriptor_;
  std::optional<place_recognition::LoopDetector> detector_;

  ros::Subscriber keyframe_subscriber_;
  ros::Publisher loop_publisher_;
  ros::ServiceServer detect_service_;

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
    // Load the vocabulary once now, so that a missing or damaged file stops start-up.
    place_recognition::Vocabulary::Load(place_options_.vocabulary_directory + "/vocabulary.bin");
  } catch (const std::exception& error) {
    NODELET_FATAL_STREAM("bad configuration: " << error.what());
    throw;
  }
  NODELET_INFO_STREAM("vocabulary " << place_options_.vocabulary_directory
                                    << "; options in force:\n"
                                    << ros_parameters::PrintedOptions(detector_options_));
  ros::NodeHandle& node = getNodeHandle();
  loop_publisher_ = node.advertise<stereo_fabmap_slam::LoopEdge>("loop_edges", 100);
  detect_service_ = node.advertiseService("detect_loop", &LoopDetectorNodelet::OnDetectLoop, this);
  worker_ = std::thread(&LoopDetectorNodelet::Work, this);
  keyframe_subscriber_ = node.subscribe("keyframes", 100, &LoopDetectorNodelet::OnKeyframe, this);
}

LoopDetectorNodelet::~LoopDetectorNodelet() {
  {
    std::lock_guard<std::mutex> lock(queue_mutex_);
    stopping_ = true;
  }
  wake_.notify_all();
  if (worker_.joinable()) worker_.join();
}

place_recognition::LoopDetector& LoopDetectorNodelet::Detector(
    const stereo_fabmap_slam::Keyframe& message) {
  if (!detector_) {
    detector_.emplace(pipeline::LoopClosing::LoadDetector(
        place_options_, detector_options_, ros_conversions::CameraOfKeyframe(message),
        descriptor_.norm, descriptor_.max_match_distance));
  }
  return *detector_;
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
        const place_recognition::LoopDetection detection =
            Detector(*message).Process(ros_conversions::FromKeyframeMessage(*message));
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

}  // namespace stereo_fabmap_slam

PLUGINLIB_EXPORT_CLASS(stereo_fabmap_slam::LoopDetectorNodelet, nodelet::Nodelet)
