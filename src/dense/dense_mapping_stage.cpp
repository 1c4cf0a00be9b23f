#include "stereo_fabmap_slam/dense/dense_mapping_stage.h"

#include <algorithm>
#include <stdexcept>
#include <utility>

#include "stereo_fabmap_slam/dense/mesh_simplification.h"
#include "stereo_fabmap_slam/dense/ply_files.h"
#include "stereo_fabmap_slam/dense/surface_comparison.h"

namespace stereo_fabmap_slam::dense {

DenseMappingStage::DenseMappingStage(const DenseMappingOptions& options,
                                     const StereoDepthOptions& depth_options,
                                     const FusionOptions& fusion_options,
                                     const camera::StereoRectifier& rectifier)
    : options_((options.Validate(), options)),
      rectifier_(rectifier),
      volume_(depth_options, fusion_options, rectifier.camera()) {}

void DenseMappingStage::AddPair(DenseStereoPair pair) {
  // A keyframe that came first takes its pair at once; the pairs wait for theirs.
  const auto keyframe = std::find_if(waiting_.begin(), waiting_.end(), [&](const DenseKeyframe& k) {
    return k.stamp_ns == pair.stamp_ns;
  });
  if (keyframe != waiting_.end()) {
    ready_.push_back(Ready{*keyframe, std::move(pair)});
    waiting_.erase(keyframe);
    return;
  }
  pairs_.push_back(std::move(pair));
  while (pairs_.size() > static_cast<std::size_t>(options_.buffered_pairs)) pairs_.pop_front();
}

void DenseMappingStage::AddKeyframe(const DenseKeyframe& keyframe) {
  // The newest pairs first: a keyframe is made from one of the last few.
  const auto pair = std::find_if(pairs_.rbegin(), pairs_.rend(), [&](const DenseStereoPair& p) {
    return p.stamp_ns == keyframe.stamp_ns;
  });
  if (pair != pairs_.rend()) {
    ready_.push_back(Ready{keyframe, *pair});  // cv::Mat shares the images
    return;
  }
  waiting_.push_back(keyframe);
  while (waiting_.size() > static_cast<std::size_t>(options_.buffered_pairs)) {
    left_out_.push_back("keyframe " + std::to_string(waiting_.front().id) +
                        ": its stereo pair did not come");
    waiting_.pop_front();
  }
}

void DenseMappingStage::SetMap(const Eigen::Isometry3d& T_map_odom,
                               std::map<std::uint64_t, Eigen::Isometry3d> keyframe_poses) {
  T_map_odom_ = T_map_odom;
  map_poses_ = std::move(keyframe_poses);
  moves_pending_ = true;  // Step finds out whether any keyframe moved far enough
}

void DenseMappingStage::Add(DenseInput input) {
  if (auto* pair = std::get_if<DenseStereoPair>(&input)) {
    AddPair(std::move(*pair));
  } else if (const auto* keyframe = std::get_if<DenseKeyframe>(&input)) {
    AddKeyframe(*keyframe);
  } else {
    DenseMapUpdate& map = std::get<DenseMapUpdate>(input);
    SetMap(map.T_map_odom, std::move(map.keyframe_poses));
  }
}

Eigen::Isometry3d DenseMappingStage::MapPose(const DenseKeyframe& keyframe) const {
  const auto in_map = map_poses_.find(keyframe.id);
  return in_map != map_poses_.end() ? in_map->second : T_map_odom_ * keyframe.T_odom_camera;
}

void DenseMappingStage::Fuse(const Ready& ready, DenseStepReport* report) {
  cv::Mat left, right;
  try {
    rectifier_.Rectify(ready.pair.left, ready.pair.right, &left, &right);
  } catch (const std::invalid_argument& error) {  // not of the calibrated size
    report->left_out.push_back("keyframe " + std::to_string(ready.keyframe.id) + ": " +
                               error.what());
    return;
  }
  DenseStepReport::Fused fused{ready.keyframe.id, {}};
  if (volume_.Add(ready.keyframe.id, left, right, MapPose(ready.keyframe), &fused.timing)) {
    report->fused.push_back(fused);
    fused_timings_.push_back(fused.timing);
  }
}

DenseStepReport DenseMappingStage::Step() {
  DenseStepReport report;
  report.left_out.swap(left_out_);
  const std::size_t fused_before = fused_timings_.size();
  while (!ready_.empty()) {
    const Ready ready = std::move(ready_.front());
    ready_.pop_front();
    Fuse(ready, &report);
  }
  constexpr std::size_t kEvery = DenseStepReport::Progress::kEvery;
  if (fused_timings_.size() / kEvery != fused_before / kEvery) {
    report.progress =
        DenseStepReport::Progress{volume_.keyframes(), RecentFuseMedianMs(kEvery),
                                  volume_.fusion().blocks(), volume_.memory_bytes() / 1048576.0};
  }
  if (moves_pending_) {
    const auto most = static_cast<std::size_t>(options_.moves_per_step);
    report.moved = volume_.Move(map_poses_, most);
    report.still_moving = report.moved == most ? volume_.Moving(map_poses_) : 0;
    moves_pending_ = report.still_moving > 0;
  }
  view_changed_ = view_changed_ || report.changed();
  return report;
}

double DenseMappingStage::RecentFuseMedianMs(std::size_t count) const {
  const std::size_t first = fused_timings_.size() - std::min(count, fused_timings_.size());
  std::vector<double> fuse_ms;
  for (std::size_t k = first; k < fused_timings_.size(); ++k)
    fuse_ms.push_back(fused_timings_[k].depth_ms + fused_timings_[k].fusion_ms);
  return fuse_ms.empty() ? 0.0 : Quantile(fuse_ms, 0.5);
}

Mesh DenseMappingStage::ViewerMesh(std::size_t max_triangles) const {
  Mesh mesh = volume_.ExtractMesh();
  for (double cell = 2.0 * volume_.fusion().options().voxel_size;
       mesh.triangles.size() > max_triangles; cell *= 2.0) {
    mesh = SimplifiedMesh(mesh, cell);
  }
  return mesh;
}

Mesh DenseMappingStage::SaveMesh(const std::string& path) const {
  Mesh mesh = volume_.ExtractMesh();
  WriteMeshPly(mesh, path);
  return mesh;
}

std::size_t DenseMappingStage::SaveCloud(const std::string& path) const {
  const Cloud cloud = volume_.ExtractCloud();
  WriteCloudPly(cloud, path);
  return cloud.points.size();
}

}  // namespace stereo_fabmap_slam::dense
