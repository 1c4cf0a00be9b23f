#include "place_wiring.h"

#include <chrono>
#include <stdexcept>

#include "parameter_reader.h"
#include "ros_conversions.h"
#include "stereo_fabmap_slam/place_recognition/vocabulary.h"

namespace stereo_fabmap_slam::ros_wiring {

PlaceParameters ReadPlaceParameters(const ros::NodeHandle& private_node) {
  PlaceParameters p;
  const features::FeatureOptions odometry_features =
      ros_parameters::ReadModuleOptions(private_node, features::FeatureOptions());
  p.descriptor = features::CreateDescriptor(odometry_features);
  std::string fabmap_config;
  if (!private_node.getParam("fabmap_config", fabmap_config)) {
    throw std::invalid_argument("set ~fabmap_config (e.g. config/fabmap.yaml)");
  }
  p.place = place_recognition::LoadPlaceRecognitionOptions(fabmap_config, odometry_features);
  p.detection = ros_parameters::ReadModuleOptions(private_node, p.detection);
  p.relocalizer = ros_parameters::ReadModuleOptions(private_node, p.relocalizer);
  p.printed =
      ros_parameters::PrintedOptions(p.detection) + ros_parameters::PrintedOptions(p.relocalizer);
  // Loaded once now, so that a missing or damaged vocabulary stops start-up.
  place_recognition::Vocabulary::Load(p.place.vocabulary_directory + "/vocabulary.bin");
  p.map_file = private_node.param<std::string>("map_file", "");
  p.save_map_at_exit = private_node.param<std::string>("save_map", "");
  p.mode = private_node.param<std::string>("mode", "mapping");
  ros_parameters::RejectUnknownParameters(
      private_node, {"config_file", "fabmap_config", "map_file", "mode", "save_map"});
  return p;
}

void KeyframePairing::AddKeyframe(const stereo_fabmap_slam::KeyframeConstPtr& keyframe) {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    keyframes_[keyframe->id] = keyframe;
    // Bounded: keyframes no Backend answers (none runs) are not kept for ever.
    constexpr std::size_t kMostWaiting = 1000;
    if (keyframes_.size() > kMostWaiting) keyframes_.erase(keyframes_.begin());
    newest_keyframe_ = any_keyframe_ ? std::max(newest_keyframe_, keyframe->id) : keyframe->id;
    any_keyframe_ = true;
  }
  changed_.notify_all();
}

void KeyframePairing::AddUpdate(const stereo_fabmap_slam::KeyframeUpdateConstPtr& update) {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    updates_.push_back(update);
  }
  changed_.notify_all();
}

std::optional<KeyframePairing::Pair> KeyframePairing::Ready() {
  if (updates_.empty()) return std::nullopt;
  const std::uint64_t id = updates_.front()->keyframe_id;
  const auto it = keyframes_.find(id);
  // Keyframes come in order of id: one newer than this answer's having come, its own never will.
  if (it == keyframes_.end() && !(any_keyframe_ && newest_keyframe_ > id)) return std::nullopt;
  Pair pair{it == keyframes_.end() ? nullptr : it->second, updates_.front()};
  updates_.pop_front();
  // Keyframes up to this one are answered or never will be.
  keyframes_.erase(keyframes_.begin(), keyframes_.upper_bound(id));
  return pair;
}

std::optional<KeyframePairing::Pair> KeyframePairing::Take() {
  std::unique_lock<std::mutex> lock(mutex_);
  std::optional<Pair> pair;
  changed_.wait(lock, [&] { return stopping_ || (pair = Ready()).has_value(); });
  if (stopping_) return std::nullopt;
  return pair;
}

void KeyframePairing::Stop() {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    stopping_ = true;
  }
  changed_.notify_all();
}

pipeline::PlaceService MakePlaceService(const PlaceParameters& parameters) {
  // Copied: the service outlives no parameters it refers to.
  return pipeline::PlaceService([parameters](const geometry::StereoCamera& camera) {
    return pipeline::PlaceStage(
        pipeline::PlaceStage::LoadDetector(parameters.place, parameters.detection, camera,
                                           parameters.descriptor.norm,
                                           parameters.descriptor.max_match_distance),
        parameters.relocalizer, [] {
          return std::chrono::duration<double, std::milli>(
                     std::chrono::steady_clock::now().time_since_epoch())
              .count();
        });
  });
}

void FillMapFileResponse(const pipeline::MapFileAnswer& answer,
                         stereo_fabmap_slam::MapFile::Response* response) {
  response->success = answer.success;
  response->keyframes = static_cast<std::uint32_t>(answer.keyframes);
  response->message = answer.message;
}

void FillDetectLoopResponse(const place_recognition::LoopDetection& detection,
                            stereo_fabmap_slam::DetectLoop::Response* response) {
  if (detection.places_compared == 0) {
    response->message = "the map has no place old enough to compare with";
    response->new_place_probability = 1;
    response->success = false;
    return;
  }
  response->success = true;
  response->new_place_probability = detection.new_place_probability;
  for (const place_recognition::LoopCandidate& candidate : detection.candidates) {
    response->candidate_ids.push_back(static_cast<std::uint64_t>(candidate.keyframe_id));
    response->candidate_probabilities.push_back(candidate.probability);
    response->candidate_inliers.push_back(candidate.inliers);
    response->candidate_accepted.push_back(candidate.accepted);
    response->candidate_reasons.push_back(candidate.reason);
  }
  response->loop_found = detection.loop.has_value();
  if (detection.loop) response->loop = ros_conversions::ToLoopEdgeMessage(*detection.loop);
  response->message = std::to_string(detection.candidates.size()) + " candidates" +
                      (detection.loop ? ", loop found" : ", no loop");
}

}  // namespace stereo_fabmap_slam::ros_wiring
