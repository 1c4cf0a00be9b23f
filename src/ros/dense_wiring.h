#pragma once

// The DenseMapper nodelet's plumbing, apart from the nodelet so that it stays wiring only: its
// parameters and its messages as the dense mapping stage's inputs. Nothing here decides anything
// about the dense map (dense::DenseMappingStage does, driven by dense::DenseMappingWorker as
// run_dataset drives it).

#include <optional>
#include <string>

#include <ros/node_handle.h>
#include <stereo_fabmap_slam/Keyframe.h>
#include <stereo_fabmap_slam/MapGraph.h>

#include "stereo_fabmap_slam/camera/stereo_rectifier.h"
#include "stereo_fabmap_slam/dense/dense_mapping_stage.h"
#include "stereo_fabmap_slam/dense/dense_mapping_worker.h"
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
  dense::DenseWorkerOptions worker;  // ~rate (view_rate) and ~save_mesh (save_mesh_at_stop)
  double cloud_cell = 0.05;          // [m] one point of dense_cloud a cube of this edge
  // Triangles of dense_mesh at most (the mesh simplified until it fits): 100,000 are 12 MB a
  // message.
  int max_mesh_triangles = 100000;
  std::string printed;
};

// Throws std::invalid_argument (or the options' errors) for a bad configuration.
DenseMapperParameters ReadDenseMapperParameters(const ros::NodeHandle& private_node);

// The messages as the stage's inputs; a pair's images are copied (the stage keeps them beyond
// the message). nullopt and why for a pair that is not an image the stage can take.
std::optional<dense::DenseInput> DenseInputOf(const ImagePair& pair, std::string* refusal);
dense::DenseInput DenseInputOf(const stereo_fabmap_slam::Keyframe& keyframe);
dense::DenseInput DenseInputOf(const stereo_fabmap_slam::MapGraph& graph);

}  // namespace stereo_fabmap_slam::ros_wiring
