#pragma once

// The DenseMapper nodelet's plumbing, apart from the nodelet so that it stays wiring only: its
// inputs as they arrive, and each handed to the dense mapping stage. Nothing here decides
// anything about the dense map (dense::DenseMappingStage does).

#include <string>
#include <variant>

#include <stereo_fabmap_slam/Keyframe.h>
#include <stereo_fabmap_slam/MapGraph.h>

#include "arrival_queue.h"
#include "stereo_fabmap_slam/dense/dense_mapping_stage.h"
#include "tracker_wiring.h"

namespace stereo_fabmap_slam::ros_wiring {

// Every input of the DenseMapper, as it arrived.
using DenseMapperInput = std::variant<ImagePair, stereo_fabmap_slam::KeyframeConstPtr,
                                      stereo_fabmap_slam::MapGraphConstPtr>;
using DenseMapperQueue = ArrivalQueue<DenseMapperInput>;

// Hands the input to the stage: a pair's images are copied (the stage keeps them beyond the
// message). Returns why a pair was refused (not an image the stage can take), else "".
std::string PassToStage(const DenseMapperInput& input, dense::DenseMappingStage* stage);

}  // namespace stereo_fabmap_slam::ros_wiring
