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

}  // namespace stereo_fabmap_slam::ros_wiring
