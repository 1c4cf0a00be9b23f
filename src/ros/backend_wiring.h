#pragma once

// The Backend nodelet's plumbing, apart from the nodelet so that it stays wiring only and this
// is unit-tested: every input in the order it arrived, handed to the worker all at once, and
// its conversion to the mapping stage's input. Nothing here decides anything about the map.

#include <string>
#include <variant>
#include <vector>

#include <std_msgs/Header.h>
#include <stereo_fabmap_slam/Keyframe.h>
#include <stereo_fabmap_slam/LoopEdge.h>
#include <stereo_fabmap_slam/PlaceResult.h>

#include "stereo_fabmap_slam/concurrency/arrival_queue.h"
#include "stereo_fabmap_slam/pipeline/mapping_stage.h"

namespace stereo_fabmap_slam::ros_wiring {

// A map file the LoopDetector took (map_loaded): the Backend rebuilds its graph from the file.
struct MapFileLoaded {
  std::string path;
};
// Every input of the Backend, as it arrived.
using BackendInput =
    std::variant<stereo_fabmap_slam::KeyframeConstPtr, stereo_fabmap_slam::PlaceResultConstPtr,
                 stereo_fabmap_slam::LoopEdgeConstPtr, MapFileLoaded, pipeline::SlamMode,
                 pipeline::LocalizationCorrectionInput>;

// The mapping stage's input of a message; throws for a map file that cannot be read.
pipeline::MappingInput ToMappingInput(const BackendInput& input);
// A keyframe's header (its keyframe update carries it), else an empty one.
std_msgs::Header HeaderOf(const BackendInput& input);

// The Backend worker's inputs. Under load the stage adjusts the newest of the waiting
// keyframes together (MappingStage::Take).
using BackendQueue = concurrency::ArrivalQueue<BackendInput>;

}  // namespace stereo_fabmap_slam::ros_wiring
