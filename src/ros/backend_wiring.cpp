#include "backend_wiring.h"

#include "ros_conversions.h"
#include "stage_conversions.h"
#include "stereo_fabmap_slam/map/map_file.h"

namespace stereo_fabmap_slam::ros_wiring {

pipeline::MappingInput ToMappingInput(const BackendInput& input) {
  if (const auto* keyframe = std::get_if<stereo_fabmap_slam::KeyframeConstPtr>(&input)) {
    return pipeline::KeyframeInput{ros_conversions::FromKeyframeMessage(**keyframe),
                                   ros_conversions::CameraOfKeyframe(**keyframe)};
  }
  if (const auto* place = std::get_if<stereo_fabmap_slam::PlaceResultConstPtr>(&input)) {
    const pipeline::PlaceResult result = ros_conversions::FromPlaceResultMessage(**place);
    return pipeline::LoopDetectionInput{result.keyframe_id, result.detection.loop};
  }
  if (const auto* edge = std::get_if<stereo_fabmap_slam::LoopEdgeConstPtr>(&input)) {
    return pipeline::RelocalizationEdgeInput{ros_conversions::FromLoopEdgeMessage(**edge)};
  }
  if (const auto* load = std::get_if<MapFileLoaded>(&input)) {
    // The LoopDetector checked the file; the graph is rebuilt from the same file.
    return pipeline::LoadedMapInput{map::LoadMapFile(load->path), load->path};
  }
  if (const auto* mode = std::get_if<pipeline::SlamMode>(&input)) return *mode;
  return std::get<pipeline::LocalizationCorrectionInput>(input);
}

std_msgs::Header HeaderOf(const BackendInput& input) {
  if (const auto* keyframe = std::get_if<stereo_fabmap_slam::KeyframeConstPtr>(&input)) {
    return (*keyframe)->header;
  }
  return std_msgs::Header();
}

void ArrivalQueue::Push(BackendInput input) {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    inputs_.push_back(std::move(input));
  }
  wake_.notify_one();
}

std::optional<std::deque<BackendInput>> ArrivalQueue::TakeAll() {
  std::unique_lock<std::mutex> lock(mutex_);
  wake_.wait(lock, [&] { return stopping_ || !inputs_.empty(); });
  if (stopping_) return std::nullopt;
  std::deque<BackendInput> waiting;
  waiting.swap(inputs_);
  return waiting;
}

void ArrivalQueue::Stop() {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    stopping_ = true;
  }
  wake_.notify_all();
}

}  // namespace stereo_fabmap_slam::ros_wiring
