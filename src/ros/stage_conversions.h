#pragma once

// The stages' typed inputs and outputs (pipeline/) as the messages and services between the
// nodelets carry them, and back: one tested place, as ros_conversions.h is for the map's types.

#include <string>

#include <stereo_fabmap_slam/KeyframeUpdate.h>
#include <stereo_fabmap_slam/MapGraph.h>
#include <stereo_fabmap_slam/MapLoaded.h>
#include <stereo_fabmap_slam/PlaceResult.h>
#include <stereo_fabmap_slam/RelocalizeFrame.h>
#include <stereo_fabmap_slam/TrackedFrame.h>

#include "stereo_fabmap_slam/geometry/stereo_camera.h"
#include "stereo_fabmap_slam/pipeline/input_monitor.h"
#include "stereo_fabmap_slam/pipeline/mapping_stage.h"
#include "stereo_fabmap_slam/pipeline/place_stage.h"
#include "stereo_fabmap_slam/pipeline/run_record.h"

namespace stereo_fabmap_slam::ros_conversions {

// The mapping stage's answer to a keyframe (keyframe_updates). Throws std::invalid_argument for
// arrays of different lengths.
stereo_fabmap_slam::KeyframeUpdate ToMappedKeyframeMessage(const pipeline::MappedKeyframe& mapped);
pipeline::MappedKeyframe FromMappedKeyframeMessage(
    const stereo_fabmap_slam::KeyframeUpdate& message);

// The mapping stage's state (map_graph; header left to the caller), and the snapshot the other
// stages keep of it. Throws std::invalid_argument for arrays of different lengths.
stereo_fabmap_slam::MapGraph ToMapGraphMessage(const pipeline::MappingStage& mapping);
pipeline::MapSnapshot FromMapGraphMessage(const stereo_fabmap_slam::MapGraph& message);

// A loaded map, announced (map_loaded; stamped now).
stereo_fabmap_slam::MapLoaded ToMapLoadedMessage(const std::string& path,
                                                 const pipeline::LoadedMap& loaded);

// A keyframe's loop detection (place_results; the frame id left to the caller).
stereo_fabmap_slam::PlaceResult ToPlaceResultMessage(const pipeline::PlaceResult& result);
pipeline::PlaceResult FromPlaceResultMessage(const stereo_fabmap_slam::PlaceResult& message);

// One processed pair (tracked_frames), with the input's counts so far.
stereo_fabmap_slam::TrackedFrame ToTrackedFrameMessage(const pipeline::FrameRecord& frame,
                                                       const pipeline::InputCounts& counts,
                                                       const std::string& frame_id);
pipeline::FrameRecord FromTrackedFrameMessage(const stereo_fabmap_slam::TrackedFrame& message);
// A pair the input monitor refused: the counts only.
stereo_fabmap_slam::TrackedFrame RefusedFrameMessage(double timestamp,
                                                     const pipeline::InputCounts& counts,
                                                     const std::string& frame_id);

// The tracking stage's relocalization request and the place stage's answer (relocalize_frame).
stereo_fabmap_slam::RelocalizeFrame::Request ToRelocalizeFrameRequest(
    const pipeline::RelocalizationRequest& request, const geometry::StereoCamera& camera,
    const std::string& frame_id);
pipeline::RelocalizationRequest FromRelocalizeFrameRequest(
    const stereo_fabmap_slam::RelocalizeFrame::Request& message);
stereo_fabmap_slam::RelocalizeFrame::Response ToRelocalizeFrameResponse(
    const pipeline::RelocalizationAnswer& answer);
pipeline::RelocalizationAnswer FromRelocalizeFrameResponse(
    const stereo_fabmap_slam::RelocalizeFrame::Response& message);

}  // namespace stereo_fabmap_slam::ros_conversions
