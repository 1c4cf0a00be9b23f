#pragma once

// The DenseMapper nodelet's plumbing, apart from the nodelet so that it stays wiring only: its
// parameters, its inputs as they arrive, and each handed to the dense mapping stage. Nothing here
// decides anything about the dense map (dense::DenseMappingStage does).

#include <string>
#include <variant>

#include <ros/node_handle.h>
#include <stereo_fabmap_slam/Keyframe.h>
#include <stereo_fabmap_slam/MapGraph.h>

#include "arrival_queue.h"
#include "stereo_fabmap_slam/camera/stereo_rectifier.h"
#include "stereo_fabmap_slam/dense/dense_mapping_stage.h"
#include "tracker_wiring.h"

namespace stereo_fabmap_slam::ros_wiring {

// The DenseMapper's parameters (~ names as the fields; sections as the config file's).
struct DenseMapperParameters {
  camera::RectificationOptions rectification;
  dense::StereoDepthOptions depth;
  dense::FusionOptions fusion;
  dense::DenseMappingOptions mapping;
  std::string calibration_file;
  bool use_camera_info = false;
  bool approximate_sync = false;
  std::string map_frame = "map";
  int queue_size = 10;
  double rate = 0.5;         // [Hz] of dense_cloud and dense_mesh, when they changed
  double cloud_cell = 0.05;  // [m] one point of dense_cloud a cube of this edge
  // Triangles of dense_mesh at most (the mesh simplified until it fits): 100,000 are 12 MB a
  // message.
  int max_mesh_triangles = 100000;
  std::string save_mesh;  // a PLY file the mesh is written to when the nodelet shuts down
  std::string printed;
};

// Throws std::invalid_argument (or the options' errors) for a bad configuration.
DenseMapperParameters ReadDenseMapperParameters(const ros::NodeHandle& private_node);

// Every input of the DenseMapper, as it arrived.
using DenseMapperInput = std::variant<ImagePair, stereo_fabmap_slam::KeyframeConstPtr,
                                      stereo_fabmap_slam::MapGraphConstPtr>;
using DenseMapperQueue = ArrivalQueue<DenseMapperInput>;

// Hands the input to the stage: a pair's images are copied (the stage keeps them beyond the
// message). Returns why a pair was refused (not an image the stage can take), else "".
std::string PassToStage(const DenseMapperInput& input, dense::DenseMappingStage* stage);

}  // namespace stereo_fabmap_slam::ros_wiring
