// The dense mapping stage for run_dataset --dense, in a library run_dataset loads only then
// (dense_run.h).
#include "dense_run.h"

#include <cstdio>
#include <map>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "stereo_fabmap_slam/dense/dense_mapping_worker.h"
#include "stereo_fabmap_slam/dense/surface_comparison.h"

namespace stereo_fabmap_slam::tools {
namespace {

class DenseStageRun : public DenseRun {
 public:
  DenseStageRun(const dense::DenseMappingOptions& mapping, const dense::StereoDepthOptions& depth,
                const dense::FusionOptions& fusion, const camera::StereoRectifier& rectifier,
                bool concurrent, bool quiet)
      : concurrent_(concurrent),
        worker_(mapping, depth, fusion, rectifier, WorkerOptions(concurrent), Listener(quiet)) {}

  void AfterFrame(const datasets::StereoImages& images, const pipeline::FrameRecord* frame,
                  const pipeline::StereoSlam& slam) override {
    if (frame != nullptr && frame->is_keyframe) {
      // Only a keyframe's pair: here the keyframe decision comes with the pair, and with
      // --threads a queue of every pair would grow without bound behind a slower dense map.
      worker_.Push(dense::DenseStereoPair{images.timestamp_ns, images.left, images.right});
      // The tracker's reference is the keyframe it has just made.
      worker_.Push(dense::DenseKeyframe{static_cast<std::uint64_t>(frame->reference_keyframe),
                                        images.timestamp_ns, frame->T_world_camera});
    }
    // The map changes with a keyframe (bundle adjustment, a loop) or a relocalization's edge.
    if (frame != nullptr && (frame->is_keyframe || frame->relocalized)) worker_.Push(Map(slam));
    if (!concurrent_) worker_.StepNow();
  }

  void Finish(const pipeline::StereoSlam& slam) override {
    worker_.Push(Map(slam));
    worker_.Finish();
  }

  void Write(const std::string& output, pipeline::JsonObject* summary) const override {
    worker_.WithStage([&](const dense::DenseMappingStage& stage) {
      const dense::KeyframeVolume& volume = stage.volume();
      const dense::Mesh mesh = stage.SaveMesh(output + "/mesh.ply");
      stage.SaveCloud(output + "/dense_cloud.ply");
      std::vector<double> depth_ms, fusion_ms;
      for (const dense::KeyframeVolume::Timing& timing : stage.fused_timings()) {
        depth_ms.push_back(timing.depth_ms);
        fusion_ms.push_back(timing.fusion_ms);
      }
      summary->Add("dense_keyframes", depth_ms.size());
      summary->Add("dense_keyframes_moved", moved_);
      summary->Add("dense_depth_ms_median", dense::Quantile(depth_ms, 0.5), 3);
      summary->Add("dense_fusion_ms_median", dense::Quantile(fusion_ms, 0.5), 3);
      summary->Add("dense_mesh_vertices", mesh.vertices.size());
      summary->Add("dense_mesh_triangles", mesh.triangles.size());
      summary->Add("dense_mesh_area_m2", dense::SurfaceArea(mesh.vertices, mesh.triangles), 1);
      summary->Add("dense_blocks", volume.fusion().blocks());
      summary->Add("dense_volume_mb", volume.fusion().memory_bytes() / 1048576.0, 1);
      summary->Add("dense_memory_mb", volume.memory_bytes() / 1048576.0, 1);
    });
    summary->Add("dense_time_s", worker_.busy_seconds(), 3);
  }

 private:
  static dense::DenseWorkerOptions WorkerOptions(bool concurrent) {
    dense::DenseWorkerOptions options;
    options.own_thread = concurrent;
    return options;
  }

  dense::DenseWorkerListener Listener(bool quiet) {
    dense::DenseWorkerListener listener;
    listener.report = [this, quiet](const dense::DenseStepReport& report) {
      for (const std::string& left_out : report.left_out)
        if (!quiet) std::fprintf(stderr, "dense map: %s\n", left_out.c_str());
      moved_ += report.moved;  // the worker's lock held
    };
    listener.failed = [](const std::string& what) {
      std::fprintf(stderr, "dense map: %s\n", what.c_str());
    };
    return listener;
  }

  static dense::DenseMapUpdate Map(const pipeline::StereoSlam& slam) {
    // The map as the last mapped keyframe left it (with --threads the worker may be mapping one).
    const std::shared_ptr<const pipeline::MapState> map = slam.LatestMap();
    dense::DenseMapUpdate update;
    update.T_map_odom = map->MapToOdom();
    for (const auto& [id, pose] : map->MapPoses())
      update.keyframe_poses.emplace(static_cast<std::uint64_t>(id), pose);
    return update;
  }

  // Re-integrations at a pose the map moved; counted by the listener, which the worker calls
  // with its stage locked (declared before the worker: it outlives the worker's thread).
  std::size_t moved_ = 0;
  bool concurrent_;
  dense::DenseMappingWorker worker_;
};

}  // namespace
}  // namespace stereo_fabmap_slam::tools

extern "C" stereo_fabmap_slam::tools::DenseRun* stereo_fabmap_slam_create_dense_run(
    const stereo_fabmap_slam::dense::DenseMappingOptions& mapping,
    const stereo_fabmap_slam::dense::StereoDepthOptions& depth,
    const stereo_fabmap_slam::dense::FusionOptions& fusion,
    const stereo_fabmap_slam::camera::StereoRectifier& rectifier, bool concurrent, bool quiet) {
  return new stereo_fabmap_slam::tools::DenseStageRun(mapping, depth, fusion, rectifier, concurrent,
                                                      quiet);
}
