// The dense mapping stage for run_dataset --dense, in a library run_dataset loads only then
// (dense_run.h).
#include "dense_run.h"

#include <chrono>
#include <cstdio>
#include <map>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "stereo_fabmap_slam/dense/dense_mapping_stage.h"
#include "stereo_fabmap_slam/dense/surface_comparison.h"

namespace stereo_fabmap_slam::tools {
namespace {

double NowMs() {
  return std::chrono::duration<double, std::milli>(
             std::chrono::steady_clock::now().time_since_epoch())
      .count();
}

class DenseStageRun : public DenseRun {
 public:
  DenseStageRun(const dense::DenseMappingOptions& mapping, const dense::StereoDepthOptions& depth,
                const dense::FusionOptions& fusion, const camera::StereoRectifier& rectifier,
                bool quiet)
      : stage_(mapping, depth, fusion, rectifier), quiet_(quiet) {}

  void AfterFrame(const datasets::StereoImages& images, const pipeline::FrameRecord* frame,
                  const pipeline::StereoSlam& slam) override {
    const double start = NowMs();
    stage_.AddPair(dense::DenseStereoPair{images.timestamp_ns, images.left, images.right});
    if (frame != nullptr && frame->is_keyframe) {
      // The tracker's reference is the keyframe it has just made.
      stage_.AddKeyframe(dense::DenseKeyframe{static_cast<std::uint64_t>(frame->reference_keyframe),
                                              images.timestamp_ns, frame->T_world_camera});
    }
    // The map changes with a keyframe (bundle adjustment, a loop) or a relocalization's edge.
    if (frame != nullptr && (frame->is_keyframe || frame->relocalized)) SetMap(slam);
    Step();
    ms_ += NowMs() - start;
  }

  void Finish(const pipeline::StereoSlam& slam) override {
    const double start = NowMs();
    SetMap(slam);
    do Step();
    while (stage_.busy());
    ms_ += NowMs() - start;
  }

  void Write(const std::string& output, pipeline::JsonObject* summary) const override {
    const dense::KeyframeVolume& volume = stage_.volume();
    const dense::Mesh mesh = stage_.SaveMesh(output + "/mesh.ply");
    stage_.SaveCloud(output + "/dense_cloud.ply");
    std::vector<double> depth_ms, fusion_ms;
    for (const dense::KeyframeVolume::Timing& timing : stage_.fused_timings()) {
      depth_ms.push_back(timing.depth_ms);
      fusion_ms.push_back(timing.fusion_ms);
    }
    summary->Add("dense_keyframes", depth_ms.size());
    summary->Add("dense_keyframes_moved", moved_);
    summary->Add("dense_depth_ms_median", dense::Quantile(depth_ms, 0.5), 3);
    summary->Add("dense_fusion_ms_median", dense::Quantile(fusion_ms, 0.5), 3);
    summary->Add("dense_time_s", ms_ / 1000.0, 3);
    summary->Add("dense_mesh_vertices", mesh.vertices.size());
    summary->Add("dense_mesh_triangles", mesh.triangles.size());
    summary->Add("dense_mesh_area_m2", dense::SurfaceArea(mesh.vertices, mesh.triangles), 1);
    summary->Add("dense_blocks", volume.fusion().blocks());
    summary->Add("dense_volume_mb", volume.fusion().memory_bytes() / 1048576.0, 1);
    summary->Add("dense_memory_mb", volume.memory_bytes() / 1048576.0, 1);
  }

 private:
  void SetMap(const pipeline::StereoSlam& slam) {
    // The map as the last mapped keyframe left it (with --threads the worker may be mapping one).
    const std::shared_ptr<const pipeline::MapState> map = slam.LatestMap();
    std::map<std::uint64_t, Eigen::Isometry3d> poses;
    for (const auto& [id, pose] : map->MapPoses())
      poses.emplace(static_cast<std::uint64_t>(id), pose);
    stage_.SetMap(map->MapToOdom(), std::move(poses));
  }

  void Step() {
    const dense::DenseStepReport report = stage_.Step();
    for (const std::string& left_out : report.left_out)
      if (!quiet_) std::fprintf(stderr, "dense map: %s\n", left_out.c_str());
    moved_ += report.moved;
  }

  dense::DenseMappingStage stage_;
  bool quiet_;
  std::size_t moved_ = 0;  // re-integrations at a pose the map moved
  double ms_ = 0;          // all the dense mapping took
};

}  // namespace
}  // namespace stereo_fabmap_slam::tools

extern "C" stereo_fabmap_slam::tools::DenseRun* stereo_fabmap_slam_create_dense_run(
    const stereo_fabmap_slam::dense::DenseMappingOptions& mapping,
    const stereo_fabmap_slam::dense::StereoDepthOptions& depth,
    const stereo_fabmap_slam::dense::FusionOptions& fusion,
    const stereo_fabmap_slam::camera::StereoRectifier& rectifier, bool quiet) {
  return new stereo_fabmap_slam::tools::DenseStageRun(mapping, depth, fusion, rectifier, quiet);
}
