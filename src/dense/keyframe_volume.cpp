#include "stereo_fabmap_slam/dense/keyframe_volume.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <functional>
#include <utility>
#include <vector>

namespace stereo_fabmap_slam::dense {
namespace {

double Milliseconds(std::chrono::steady_clock::time_point since) {
  return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - since)
      .count();
}

// Depth in metres from millimetres and back; what is integrated is what can be taken out again.
cv::Mat Metres(const cv::Mat& millimetres) {
  cv::Mat metres;
  millimetres.convertTo(metres, CV_32F, 1e-3);
  return metres;
}

}  // namespace

KeyframeVolume::KeyframeVolume(const StereoDepthOptions& depth_options,
                               const FusionOptions& fusion_options,
                               const geometry::StereoCamera& camera)
    : stereo_(depth_options, camera),
      fusion_(fusion_options, camera),
      camera_(camera),
      voxel_size_(fusion_options.voxel_size),
      max_depth_(depth_options.max_depth),
      truncation_(fusion_options.truncation) {}

bool KeyframeVolume::Add(std::uint64_t id, const cv::Mat& left, const cv::Mat& right,
                         const Eigen::Isometry3d& T_map_camera, Timing* timing) {
  if (kept_.count(id) > 0) return false;
  const auto start = std::chrono::steady_clock::now();
  Kept kept{left.clone(), cv::Mat(), T_map_camera, {}};
  stereo_.Depth(left, right).convertTo(kept.depth_mm, CV_16U, 1e3);  // rounds, saturates
  const double depth_ms = Milliseconds(start);
  const auto fusion_start = std::chrono::steady_clock::now();
  kept.blocks = fusion_.Integrate(kept.grey, Metres(kept.depth_mm), T_map_camera);
  if (timing != nullptr) *timing = Timing{depth_ms, Milliseconds(fusion_start)};
  kept_.emplace(id, std::move(kept));
  return true;
}

double KeyframeVolume::Shift(const Eigen::Isometry3d& from, const Eigen::Isometry3d& to) const {
  // A surface at the depth limit shifts by the translation plus the rotation's arc there.
  const Eigen::Isometry3d change = from.inverse() * to;
  return change.translation().norm() + Eigen::AngleAxisd(change.linear()).angle() * max_depth_;
}

std::size_t KeyframeVolume::Moving(const std::map<std::uint64_t, Eigen::Isometry3d>& poses) const {
  std::size_t moving = 0;
  for (const auto& [id, kept] : kept_) {
    const auto pose = poses.find(id);
    if (pose != poses.end() && Shift(kept.T_map_camera, pose->second) > 0.5 * voxel_size_) ++moving;
  }
  return moving;
}

std::size_t KeyframeVolume::Move(const std::map<std::uint64_t, Eigen::Isometry3d>& poses,
                                 std::size_t max_keyframes) {
  std::vector<std::pair<double, std::uint64_t>> shifts;  // (shift, id)
  for (const auto& [id, kept] : kept_) {
    const auto pose = poses.find(id);
    if (pose == poses.end()) continue;
    const double shift = Shift(kept.T_map_camera, pose->second);
    if (shift > 0.5 * voxel_size_) shifts.emplace_back(shift, id);
  }
  std::sort(shifts.begin(), shifts.end(), std::greater<>());
  if (shifts.size() > max_keyframes) shifts.resize(max_keyframes);
  for (const auto& [shift, id] : shifts) {
    Kept& kept = kept_.at(id);
    const Eigen::Isometry3d& pose = poses.at(id);
    const cv::Mat depth = Metres(kept.depth_mm);
    fusion_.Deintegrate(kept.grey, depth, kept.T_map_camera, kept.blocks);
    kept.blocks = fusion_.Integrate(kept.grey, depth, pose);
    kept.T_map_camera = pose;
  }
  return shifts.size();
}

ViewFacingSurface KeyframeVolume::FacingKeyframes() const {
  std::vector<Eigen::Isometry3d> views;
  views.reserve(kept_.size());
  for (const auto& [id, kept] : kept_) views.push_back(kept.T_map_camera);
  // A depth at the limit updates the voxels up to a band's width behind it.
  return ViewFacingSurface(std::move(views), camera_, max_depth_ + truncation_);
}

Mesh KeyframeVolume::ExtractMesh() const { return FacingKeyframes().Keep(fusion_.ExtractMesh()); }

Cloud KeyframeVolume::ExtractCloud() const {
  return FacingKeyframes().Keep(fusion_.ExtractCloud());
}

std::size_t KeyframeVolume::memory_bytes() const {
  std::size_t images = 0;
  for (const auto& [id, kept] : kept_)
    images += kept.grey.total() * kept.grey.elemSize() +
              kept.depth_mm.total() * kept.depth_mm.elemSize() +
              kept.blocks.size() * sizeof(Eigen::Vector3i);
  return fusion_.memory_bytes() + images;
}

}  // namespace stereo_fabmap_slam::dense
