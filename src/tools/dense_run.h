#pragma once

#include <string>

#include "stereo_fabmap_slam/camera/stereo_rectifier.h"
#include "stereo_fabmap_slam/datasets/euroc_sequence.h"
#include "stereo_fabmap_slam/dense/dense_options.h"
#include "stereo_fabmap_slam/pipeline/run_record.h"
#include "stereo_fabmap_slam/pipeline/stereo_slam.h"

namespace stereo_fabmap_slam::tools {

// run_dataset --dense: the dense mapping stage beside the SLAM, driven by the worker the
// DenseMapper runs in the graph (dense::DenseMappingWorker): every pair and keyframe pushed as it
// comes, the map after every frame that changed it; one step after each frame in the caller's
// thread (the same map every run), or with --threads on the worker's own thread as in the graph;
// at the end, steps until every keyframe the map moved is fused at its final pose. It lives in a
// library of its own that run_dataset loads only with --dense: Open3D and the VTK it brings cost
// some 29 MB of memory at start-up, which a run without a dense map should not carry.
class DenseRun {
 public:
  virtual ~DenseRun() = default;
  virtual void AfterFrame(const datasets::StereoImages& images, const pipeline::FrameRecord* frame,
                          const pipeline::StereoSlam& slam) = 0;
  virtual void Finish(const pipeline::StereoSlam& slam) = 0;
  // mesh.ply and dense_cloud.ply into `output`, and the figures into the summary.
  virtual void Write(const std::string& output, pipeline::JsonObject* summary) const = 0;
};

// The library's entry point (extern "C", found with dlsym): a new DenseRun the caller deletes.
// Throws what the dense stage's constructor throws (std::invalid_argument for bad options).
using CreateDenseRunFunction = DenseRun* (*)(const dense::DenseMappingOptions& mapping,
                                             const dense::StereoDepthOptions& depth,
                                             const dense::FusionOptions& fusion,
                                             const camera::StereoRectifier& rectifier,
                                             bool concurrent, bool quiet);
inline constexpr char kDenseRunLibrary[] = "libstereo_fabmap_slam_dense_run.so";
inline constexpr char kCreateDenseRunSymbol[] = "stereo_fabmap_slam_create_dense_run";

}  // namespace stereo_fabmap_slam::tools
