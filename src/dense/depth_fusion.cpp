#include "stereo_fabmap_slam/dense/depth_fusion.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <stdexcept>
#include <unordered_set>
#include <utility>

#include <open3d/geometry/PointCloud.h>
#include <open3d/geometry/TriangleMesh.h>
#include <open3d/pipelines/integration/ScalableTSDFVolume.h>
#include <open3d/pipelines/integration/UniformTSDFVolume.h>
#include <open3d/utility/Helper.h>
#include <opencv2/core/utility.hpp>

namespace stereo_fabmap_slam::dense {

DepthFusion::DepthFusion(const FusionOptions& options, const geometry::StereoCamera& camera)
    : options_(options), camera_(camera) {
  options_.Validate();
  Reset();
}

DepthFusion::~DepthFusion() = default;

void DepthFusion::Reset() {
  volume_ = std::make_unique<open3d::pipelines::integration::ScalableTSDFVolume>(
      options_.voxel_size, options_.truncation,
      open3d::pipelines::integration::TSDFVolumeColorType::Gray32, options_.block_resolution);
}

void DepthFusion::Integrate(const cv::Mat& grey, const cv::Mat& depth,
                            const Eigen::Isometry3d& T_world_camera) {
  Fuse(grey, depth, T_world_camera, 1.0);
}

void DepthFusion::Deintegrate(const cv::Mat& grey, const cv::Mat& depth,
                              const Eigen::Isometry3d& T_world_camera) {
  Fuse(grey, depth, T_world_camera, -1.0);
}

std::vector<Eigen::Vector3i> DepthFusion::BlocksNearSurface(
    const cv::Mat& depth, const Eigen::Isometry3d& T_world_camera) const {
  // Every block the truncation band around a measured surface point passes through: the
  // segment from truncation in front of the point to truncation behind it, along the ray; every
  // block it meets lies in the box its two ends span.
  // Every second pixel: at 2 px the samples lie under 2 cm apart on a surface 4 m away.
  constexpr int kStride = 2;
  const double unit = volume_->volume_unit_length_;
  std::unordered_set<Eigen::Vector3i, open3d::utility::hash_eigen<Eigen::Vector3i>> blocks;
  for (int v = 0; v < depth.rows; v += kStride) {
    const float* row = depth.ptr<float>(v);
    for (int u = 0; u < depth.cols; u += kStride) {
      if (!(row[u] > 0.0f)) continue;
      const Eigen::Vector3d ray((u - camera_.cx) / camera_.fx, (v - camera_.cy) / camera_.fy, 1.0);
      const double along = options_.truncation / ray.norm();  // depth change of the band
      const Eigen::Vector3d near = T_world_camera * (ray * (row[u] - along));
      const Eigen::Vector3d far = T_world_camera * (ray * (row[u] + along));
      const Eigen::Vector3i a = (near / unit).array().floor().cast<int>();
      const Eigen::Vector3i b = (far / unit).array().floor().cast<int>();
      for (int x = std::min(a.x(), b.x()); x <= std::max(a.x(), b.x()); ++x)
        for (int y = std::min(a.y(), b.y()); y <= std::max(a.y(), b.y()); ++y)
          for (int z = std::min(a.z(), b.z()); z <= std::max(a.z(), b.z()); ++z)
            blocks.insert(Eigen::Vector3i(x, y, z));
    }
  }
  return std::vector<Eigen::Vector3i>(blocks.begin(), blocks.end());
}

void DepthFusion::Fuse(const cv::Mat& grey, const cv::Mat& depth,
                       const Eigen::Isometry3d& T_world_camera, double sign) {
  if (grey.type() != CV_8UC1 || depth.type() != CV_32FC1 || grey.size() != camera_.size ||
      depth.size() != camera_.size) {
    throw std::invalid_argument(
        "DepthFusion: an 8-bit grey image and a float depth image of the camera's size expected");
  }
  using open3d::pipelines::integration::UniformTSDFVolume;
  const Eigen::Isometry3d T_camera_world = T_world_camera.inverse();
  const Eigen::Matrix3d R = T_camera_world.linear();
  const Eigen::Vector3d t = T_camera_world.translation();
  const double unit = volume_->volume_unit_length_;
  const int resolution = volume_->volume_unit_resolution_;
  // The blocks first, here (the map of blocks is not thread-safe), then their voxels in
  // parallel: each voxel is updated once per view, so the result does not depend on the order.
  std::vector<UniformTSDFVolume*> blocks;
  for (const Eigen::Vector3i& index : BlocksNearSurface(depth, T_world_camera)) {
    auto found = volume_->volume_units_.find(index);
    if (found == volume_->volume_units_.end()) {
      if (sign < 0) continue;  // nothing of this view was there
      open3d::pipelines::integration::ScalableTSDFVolume::VolumeUnit created;
      created.index_ = index;
      created.volume_ = std::make_shared<UniformTSDFVolume>(
          unit, resolution, options_.truncation,
          open3d::pipelines::integration::TSDFVolumeColorType::Gray32, index.cast<double>() * unit);
      found = volume_->volume_units_.emplace(index, created).first;
    }
    blocks.push_back(found->second.volume_.get());
  }
  cv::parallel_for_(cv::Range(0, static_cast<int>(blocks.size())), [&](const cv::Range& range) {
    for (int b = range.start; b < range.end; ++b) {
      UpdateBlock(grey, depth, R, t, sign, blocks[static_cast<std::size_t>(b)]);
    }
  });
}

void DepthFusion::UpdateBlock(const cv::Mat& grey, const cv::Mat& depth, const Eigen::Matrix3d& R,
                              const Eigen::Vector3d& t, double sign,
                              open3d::pipelines::integration::UniformTSDFVolume* volume) const {
  open3d::pipelines::integration::UniformTSDFVolume& block = *volume;
  const int resolution = block.resolution_;
  const double voxel = options_.voxel_size;
  const Eigen::Vector3d origin = block.origin_;
  for (int x = 0; x < resolution; ++x) {
    for (int y = 0; y < resolution; ++y) {
      // The column of voxels along z, in the camera frame: start and step.
      const Eigen::Vector3d start =
          R * (origin + voxel * Eigen::Vector3d(x + 0.5, y + 0.5, 0.5)) + t;
      const Eigen::Vector3d step = R.col(2) * voxel;
      for (int z = 0; z < resolution; ++z) {
        const Eigen::Vector3d p = start + z * step;
        if (p.z() <= 1e-3) continue;
        const int u = static_cast<int>(std::lround(camera_.fx * p.x() / p.z() + camera_.cx));
        const int v = static_cast<int>(std::lround(camera_.fy * p.y() / p.z() + camera_.cy));
        if (u < 0 || v < 0 || u >= depth.cols || v >= depth.rows) continue;
        const double measured = depth.at<float>(v, u);
        if (!(measured > 0.0)) continue;
        // Signed distance along the ray (Open3D's convention), positive in front of the
        // surface; truncated; nothing behind the band (unseen).
        const double distance =
            (measured - p.z()) * std::sqrt(1.0 + (p.x() * p.x() + p.y() * p.y()) / (p.z() * p.z()));
        if (distance < -options_.truncation) continue;
        const double tsdf = std::min(1.0, distance / options_.truncation);
        // Inverse variance: stereo depth's error grows with the square of the depth, its
        // variance with the fourth power (1 at 1 m).
        const double weight = sign / (measured * measured * measured * measured);
        open3d::geometry::TSDFVoxel& cell =
            block.voxels_[static_cast<std::size_t>(block.IndexOf(x, y, z))];
        const double total = cell.weight_ + weight;
        // All of it taken out again: the stored weight is a float, so what is left is
        // rounding, not an observation (relative to the weight taken out).
        if (total <= 1e-4 * std::abs(weight)) {
          cell.tsdf_ = 0.0f;
          cell.weight_ = 0.0f;
          cell.color_.setZero();
          continue;
        }
        const double g = grey.at<std::uint8_t>(v, u) / 255.0;
        cell.tsdf_ = static_cast<float>((cell.tsdf_ * cell.weight_ + tsdf * weight) / total);
        cell.color_ = (cell.color_ * cell.weight_ + Eigen::Vector3d::Constant(g) * weight) / total;
        cell.weight_ = static_cast<float>(total);
      }
    }
  }
}

Mesh DepthFusion::ExtractMesh() const {
  const std::shared_ptr<open3d::geometry::TriangleMesh> extracted = volume_->ExtractTriangleMesh();
  Mesh mesh;
  mesh.vertices = std::move(extracted->vertices_);
  mesh.triangles = std::move(extracted->triangles_);
  mesh.grey.reserve(extracted->vertex_colors_.size());
  // Gray32 volumes give every colour channel the grey level.
  for (const Eigen::Vector3d& colour : extracted->vertex_colors_)
    mesh.grey.push_back(static_cast<float>(colour.x()));
  return mesh;
}

Cloud DepthFusion::ExtractCloud() const {
  const std::shared_ptr<open3d::geometry::PointCloud> extracted = volume_->ExtractPointCloud();
  Cloud cloud;
  cloud.points = std::move(extracted->points_);
  cloud.normals = std::move(extracted->normals_);
  cloud.grey.reserve(extracted->colors_.size());
  for (const Eigen::Vector3d& colour : extracted->colors_)
    cloud.grey.push_back(static_cast<float>(colour.x()));
  return cloud;
}

std::size_t DepthFusion::blocks() const { return volume_->volume_units_.size(); }

std::size_t DepthFusion::memory_bytes() const {
  // Open3D keeps every voxel of an allocated block: its grid index, colour (doubles), signed
  // distance and weight.
  const std::size_t voxels_per_block = static_cast<std::size_t>(options_.block_resolution) *
                                       options_.block_resolution * options_.block_resolution;
  return blocks() * voxels_per_block * sizeof(open3d::geometry::TSDFVoxel);
}

}  // namespace stereo_fabmap_slam::dense
