#include "stereo_fabmap_slam/dense/depth_fusion.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <stdexcept>
#include <string>
#include <unordered_set>
#include <utility>

#include <open3d/core/Tensor.h>
#include <open3d/core/hashmap/HashMap.h>
#include <open3d/t/geometry/PointCloud.h>
#include <open3d/t/geometry/TriangleMesh.h>
#include <open3d/t/geometry/VoxelBlockGrid.h>
#include <open3d/utility/Helper.h>
#include <opencv2/core/utility.hpp>

namespace stereo_fabmap_slam::dense {
namespace {

namespace o3c = open3d::core;

// Blocks the grid is created for; the hash map grows (rehashes) beyond it.
constexpr std::int64_t kInitialBlocks = 4096;
// Bytes a voxel keeps: signed distance and weight (32-bit floats), grey level (8 bits).
constexpr std::size_t kBytesPerVoxel = sizeof(float) + sizeof(float) + sizeof(std::uint8_t);

o3c::Tensor BlockKeys(const std::vector<Eigen::Vector3i>& blocks) {
  std::vector<int> flat;
  flat.reserve(3 * blocks.size());
  for (const Eigen::Vector3i& block : blocks)
    flat.insert(flat.end(), {block.x(), block.y(), block.z()});
  return o3c::Tensor(flat, {static_cast<std::int64_t>(blocks.size()), 3}, o3c::Int32);
}

// The standard deviation of a stereo depth [m]: sigma_z = noise * z^2 / (f * b). Here, not a
// member, so that the compiler inlines it into the voxel loop (a member of a shared library is
// called through the PLT).
inline double DepthDeviation(double depth, double disparity_noise, double focal_baseline) {
  return disparity_noise * depth * depth / focal_baseline;
}

// std::lround(x) for |x| < 2^52, where x minus its truncation is exact, but inlined: std::lround
// is a libm call through the PLT, once for every voxel updated.
inline long RoundHalfAwayFromZero(double x) {
  const long whole = static_cast<long>(x);
  const double fraction = x - static_cast<double>(whole);
  return whole + (fraction >= 0.5 ? 1 : 0) - (fraction <= -0.5 ? 1 : 0);
}

}  // namespace

struct DepthFusion::Volume {
  Volume(double voxel_size, int resolution, std::int64_t capacity = kInitialBlocks)
      : grid({"tsdf", "weight", "grey"}, {o3c::Float32, o3c::Float32, o3c::UInt8}, {{1}, {1}, {1}},
             static_cast<float>(voxel_size), resolution, capacity) {}

  // The grid's hash map shares its storage with the grid (rehashing included).
  o3c::HashMap map() { return grid.GetHashMap(); }

  open3d::t::geometry::VoxelBlockGrid grid;
};

struct DepthFusion::ViewData {
  const cv::Mat& grey;
  const cv::Mat& depth;
  const float* depth_and_ray;  // per pixel, row by row: depth, then the ray's length per depth
  Eigen::Matrix3d R;           // world to camera
  Eigen::Vector3d t;
  float* tsdf;
  float* weight;
  std::uint8_t* grey_levels;
};

DepthFusion::DepthFusion(const FusionOptions& options, const geometry::StereoCamera& camera)
    : options_(options), camera_(camera), ray_length_(camera.size, CV_32F) {
  options_.Validate();
  for (int v = 0; v < camera_.size.height; ++v) {
    for (int u = 0; u < camera_.size.width; ++u) {
      const double x = (u - camera_.cx) / camera_.fx, y = (v - camera_.cy) / camera_.fy;
      ray_length_.at<float>(v, u) = static_cast<float>(std::sqrt(1.0 + x * x + y * y));
    }
  }
  Reset();
}

DepthFusion::~DepthFusion() = default;

void DepthFusion::Reset() {
  volume_ = std::make_unique<Volume>(options_.voxel_size, options_.block_resolution);
}

std::size_t DepthFusion::VoxelsPerBlock() const {
  const auto resolution = static_cast<std::size_t>(options_.block_resolution);
  return resolution * resolution * resolution;
}

void DepthFusion::MakeRoomFor(std::int64_t blocks) {
  o3c::HashMap old = volume_->map();
  if (old.Size() + blocks <= old.GetCapacity()) return;
  // Open3D's own growth (HashMap::Reserve, called by Activate when full) copies the keys and
  // every voxel through Tensor::IndexGet and inserts them again: on MH01_first10s its three
  // doublings took about 1 s of the 2.1 s of dense work (perf, callers by DWARF unwinding;
  // 1.3 s with this), and on a long route each one stalls the map for longer. Here the same
  // doubling, the keys activated in a grid of the new capacity and each block's voxels copied
  // whole: the same blocks at the same values (their places in the buffers change, which
  // nothing keeps), the three doublings on MH01_first10s in 0.19 s (27, 49 and 109 ms for
  // 2,888, 5,208 and 13,124 blocks, about 8 us a block; the hall loop's five in 1.0 s).
  // `blocks` counts a view's blocks near its surface, new or not, so this may double a view
  // earlier than Open3D would: the same capacity at the end on MH01_first10s and the hall
  // loop (144.4 and 577.5 MB).
  const std::int64_t capacity = std::max(2 * old.GetCapacity(), old.Size() + blocks);
  auto grown = std::make_unique<Volume>(options_.voxel_size, options_.block_resolution, capacity);
  o3c::HashMap fresh = grown->map();
  const o3c::Tensor active = old.GetActiveIndices();
  const o3c::Tensor keys = old.GetKeyTensor().IndexGet({active.To(o3c::Int64)});
  o3c::Tensor new_indices, created;
  fresh.Activate(keys, new_indices, created);
  const int* from = active.GetDataPtr<int>();
  const int* to = new_indices.GetDataPtr<int>();
  const std::vector<o3c::Tensor> old_values = old.GetValueTensors();
  std::vector<o3c::Tensor> new_values = fresh.GetValueTensors();
  for (std::size_t k = 0; k < old_values.size(); ++k) {
    const std::size_t bytes = VoxelsPerBlock() * old_values[k].GetDtype().ByteSize();
    const auto* source = static_cast<const std::uint8_t*>(old_values[k].GetDataPtr());
    auto* target = static_cast<std::uint8_t*>(new_values[k].GetDataPtr());
    for (std::int64_t i = 0; i < active.GetLength(); ++i) {
      std::memcpy(target + static_cast<std::size_t>(to[i]) * bytes,
                  source + static_cast<std::size_t>(from[i]) * bytes, bytes);
    }
  }
  volume_ = std::move(grown);
}

std::vector<Eigen::Vector3i> DepthFusion::Integrate(const cv::Mat& grey, const cv::Mat& depth,
                                                    const Eigen::Isometry3d& T_world_camera) {
  return Fuse(grey, depth, T_world_camera, nullptr);
}

void DepthFusion::Deintegrate(const cv::Mat& grey, const cv::Mat& depth,
                              const Eigen::Isometry3d& T_world_camera,
                              const std::vector<Eigen::Vector3i>& blocks) {
  Fuse(grey, depth, T_world_camera, &blocks);
}

std::vector<Eigen::Vector3i> DepthFusion::BlocksNearSurface(
    const cv::Mat& depth, const Eigen::Isometry3d& T_world_camera) const {
  // Every block the truncation band around a measured surface point passes through: the
  // segment from truncation in front of the point to truncation behind it, along the ray; every
  // block it meets lies in the box its two ends span.
  // Every second pixel: at 2 px the samples lie under 2 cm apart on a surface 4 m away.
  constexpr int kStride = 2;
  const double unit = options_.voxel_size * options_.block_resolution;
  // Farther depths update the blocks nearer ones allocated but allocate none themselves.
  const double allocation_depth = std::sqrt(options_.max_allocation_sigma * camera_.fx *
                                            camera_.baseline / options_.disparity_noise);
  std::unordered_set<Eigen::Vector3i, open3d::utility::hash_eigen<Eigen::Vector3i>> blocks;
  for (int v = 0; v < depth.rows; v += kStride) {
    const float* row = depth.ptr<float>(v);
    for (int u = 0; u < depth.cols; u += kStride) {
      if (!(row[u] > 0.0f) || row[u] > allocation_depth) continue;
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

std::vector<Eigen::Vector3i> DepthFusion::Fuse(const cv::Mat& grey, const cv::Mat& depth,
                                               const Eigen::Isometry3d& T_world_camera,
                                               const std::vector<Eigen::Vector3i>* blocks) {
  const double sign = blocks == nullptr ? 1.0 : -1.0;
  if (grey.type() != CV_8UC1 || depth.type() != CV_32FC1 || grey.size() != camera_.size ||
      depth.size() != camera_.size) {
    throw std::invalid_argument(
        "DepthFusion: an 8-bit grey image and a float depth image of the camera's size expected");
  }
  const auto voxels_per_block = static_cast<std::int64_t>(VoxelsPerBlock());
  const std::vector<Eigen::Vector3i> near_surface =
      blocks == nullptr ? BlocksNearSurface(depth, T_world_camera) : std::vector<Eigen::Vector3i>();
  MakeRoomFor(static_cast<std::int64_t>(near_surface.size()));
  o3c::HashMap map = volume_->map();
  if (!near_surface.empty()) {
    // New blocks start empty (Open3D leaves a new block's values as they were in memory).
    o3c::Tensor buffer_indices, created;
    map.Activate(BlockKeys(near_surface), buffer_indices, created);
    const int* index = buffer_indices.GetDataPtr<int>();
    const bool* is_new = created.GetDataPtr<bool>();
    std::vector<o3c::Tensor> values = map.GetValueTensors();
    for (std::size_t i = 0; i < near_surface.size(); ++i) {
      if (!is_new[i]) continue;
      const std::int64_t first = static_cast<std::int64_t>(index[i]) * voxels_per_block;
      std::fill_n(values[0].GetDataPtr<float>() + first, voxels_per_block, 0.0f);
      std::fill_n(values[1].GetDataPtr<float>() + first, voxels_per_block, 0.0f);
      std::fill_n(values[2].GetDataPtr<std::uint8_t>() + first, voxels_per_block, 0);
    }
  }
  // Every allocated block the view sees: the blocks around its surfaces, and the ones in front
  // of them, whose voxels its free space updates.
  const Eigen::Isometry3d T_camera_world = T_world_camera.inverse();
  std::vector<std::pair<Eigen::Vector3i, int>> visible;
  if (blocks == nullptr) {
    visible = VisibleBlocks(map, depth, T_camera_world);
  } else if (!blocks->empty()) {
    o3c::Tensor buffer_indices, found;
    map.Find(BlockKeys(*blocks), buffer_indices, found);
    const int* index = buffer_indices.GetDataPtr<int>();
    const bool* is_found = found.GetDataPtr<bool>();
    for (std::size_t i = 0; i < blocks->size(); ++i)
      if (is_found[i]) visible.emplace_back((*blocks)[i], index[i]);
  }
  // Each voxel reads its pixel's depth and ray length: side by side, one cache line brings both
  // (a quarter of the voxel loop's samples waited on the depth's read, perf on MH01_first10s).
  depth_and_ray_.resize(2 * depth.total());
  for (int v = 0; v < depth.rows; ++v) {
    const float* z = depth.ptr<float>(v);
    const float* ray = ray_length_.ptr<float>(v);
    float* out = depth_and_ray_.data() + 2 * static_cast<std::size_t>(v) * depth.cols;
    for (int u = 0; u < depth.cols; ++u) {
      out[2 * u] = z[u];
      out[2 * u + 1] = ray[u];
    }
  }
  std::vector<o3c::Tensor> values = map.GetValueTensors();
  const ViewData view{grey,
                      depth,
                      depth_and_ray_.data(),
                      T_camera_world.linear(),
                      T_camera_world.translation(),
                      values[0].GetDataPtr<float>(),
                      values[1].GetDataPtr<float>(),
                      values[2].GetDataPtr<std::uint8_t>()};
  // Each voxel is updated once per view, so the blocks can be updated in parallel and the result
  // does not depend on the order.
  cv::parallel_for_(cv::Range(0, static_cast<int>(visible.size())), [&](const cv::Range& range) {
    for (int b = range.start; b < range.end; ++b) {
      const auto& [block, buffer_index] = visible[static_cast<std::size_t>(b)];
      UpdateBlock(view, block, buffer_index, sign);
    }
  });
  std::vector<Eigen::Vector3i> updated;
  updated.reserve(visible.size());
  for (const auto& [block, buffer_index] : visible) updated.push_back(block);
  return updated;
}

std::vector<std::pair<Eigen::Vector3i, int>> DepthFusion::VisibleBlocks(
    open3d::core::HashMap& map, const cv::Mat& depth,
    const Eigen::Isometry3d& T_camera_world) const {
  // A block is updated only if some pixel of its voxels' image footprint measured a surface no
  // nearer than its nearest voxel minus the voxel loop's reach behind a surface (the band, and
  // behind_band_sigmas deviations); any other block would come out of the voxel loop as it went
  // in (each of its voxels projects to no depth, or to one farther than that in front of it), so
  // leaving it out changes nothing but the time. The footprint: the box of the
  // block's voxel centres projected (its corners bound it), rounded to the voxel loop's pixels;
  // the deepest measurement in it is bounded by the farthest depth of every kTile x kTile tile
  // it touches (0 where none). Most of the blocks in a view's frustum are left out so (on
  // MH01_first10s with 16-pixel tiles and a sphere's footprint, half of those kept had no voxel
  // to update).
  constexpr int kTile = 8;
  const int tiles_x = (depth.cols + kTile - 1) / kTile, tiles_y = (depth.rows + kTile - 1) / kTile;
  cv::Mat farthest(tiles_y, tiles_x, CV_32F, cv::Scalar(0.0f));
  for (int v = 0; v < depth.rows; ++v) {
    const float* row = depth.ptr<float>(v);
    float* tile_row = farthest.ptr<float>(v / kTile);
    for (int u = 0; u < depth.cols; ++u)
      tile_row[u / kTile] = std::max(tile_row[u / kTile], row[u]);
  }
  const o3c::Tensor active = map.GetActiveIndices();
  const o3c::Tensor keys = map.GetKeyTensor();
  const int* active_index = active.GetDataPtr<int>();
  const int* key = keys.GetDataPtr<int>();
  const int resolution = options_.block_resolution;
  const double unit = options_.voxel_size * resolution;
  const double half_diagonal = 0.5 * std::sqrt(3.0) * unit;
  // The voxel centres of a block span (resolution - 1) voxels along each of its axes.
  const Eigen::Matrix3d span = T_camera_world.linear() * options_.voxel_size * (resolution - 1);
  // Each block with the tile of its footprint's centre (-1 for blocks the image plane cuts): in
  // that order neighbouring blocks read the same rows of the depth image one after the other,
  // from the cache, instead of in the hash map's order (the same result: each voxel is updated
  // once).
  struct Candidate {
    int tile;
    int buffer_index;
    Eigen::Vector3i block;
  };
  std::vector<Candidate> candidates;
  for (std::int64_t i = 0; i < active.GetLength(); ++i) {
    const int buffer_index = active_index[i];
    const Eigen::Vector3i block(key[3 * buffer_index], key[3 * buffer_index + 1],
                                key[3 * buffer_index + 2]);
    // First the block's bounding sphere, cheap: most blocks of a large map are behind the
    // camera or outside the image.
    const Eigen::Vector3d centre =
        T_camera_world * ((block.cast<double>().array() + 0.5) * unit).matrix();
    if (centre.z() + half_diagonal <= 1e-3) continue;  // the voxel loop skips every voxel
    if (centre.z() - half_diagonal > 1e-3) {
      // A point within r of the centre (x, y, z) projects within f r (z + |x|) / (z (z - r)) of
      // the centre's projection along the rows (off the axis a sphere's image is wider than
      // f r / (z - r)), and likewise along the columns; a pixel more for rounding.
      const double z = centre.z(), scale = half_diagonal / (z * (z - half_diagonal));
      const double radius_u = camera_.fx * scale * (z + std::abs(centre.x())) + 1;
      const double radius_v = camera_.fy * scale * (z + std::abs(centre.y())) + 1;
      const double u = camera_.fx * centre.x() / z + camera_.cx;
      const double v = camera_.fy * centre.y() / z + camera_.cy;
      if (u + radius_u < 0 || v + radius_v < 0 || u - radius_u >= depth.cols ||
          v - radius_v >= depth.rows)
        continue;
    }
    const Eigen::Vector3d first = T_camera_world * (block.cast<double>() * unit);
    Eigen::Vector3d corners[8];
    double near = std::numeric_limits<double>::infinity(), far = -near;
    for (int c = 0; c < 8; ++c) {
      corners[c] = first + span.col(0) * (c & 1) + span.col(1) * ((c >> 1) & 1) +
                   span.col(2) * ((c >> 2) & 1);
      near = std::min(near, corners[c].z());
      far = std::max(far, corners[c].z());
    }
    if (far <= 1e-3) continue;  // behind the camera: the voxel loop skips every voxel
    int tile = -1;
    if (near > 1e-3) {
      // The voxel loop's pixel of a voxel is the floor of its projection plus a half.
      double u_low = std::numeric_limits<double>::infinity(), u_high = -u_low;
      double v_low = u_low, v_high = -u_low;
      for (const Eigen::Vector3d& corner : corners) {
        const double u = camera_.fx * corner.x() / corner.z() + camera_.cx + 0.5;
        const double v = camera_.fy * corner.y() / corner.z() + camera_.cy + 0.5;
        u_low = std::min(u_low, u);
        u_high = std::max(u_high, u);
        v_low = std::min(v_low, v);
        v_high = std::max(v_high, v);
      }
      if (u_high < -1 || v_high < -1 || u_low >= depth.cols + 1 || v_low >= depth.rows + 1)
        continue;  // outside the image
      // A pixel more on every side: the voxel loop computes its projections another way, and
      // one rounded across a pixel's edge must still be in the footprint.
      const int u0 = static_cast<int>(std::max(u_low - 1, 0.0)) / kTile;
      const int u1 = static_cast<int>(std::min(u_high + 1, depth.cols - 1.0)) / kTile;
      const int v0 = static_cast<int>(std::max(v_low - 1, 0.0)) / kTile;
      const int v1 = static_cast<int>(std::min(v_high + 1, depth.rows - 1.0)) / kTile;
      float deepest = 0.0f;
      for (int ty = v0; ty <= v1; ++ty) {
        const float* tile_row = farthest.ptr<float>(ty);
        for (int tx = u0; tx <= u1; ++tx) deepest = std::max(deepest, tile_row[tx]);
      }
      // Nothing measured, or everything farther in front of the nearest voxel than the voxel
      // loop reaches behind a depth (the band, and behind_band_sigmas of the deepest depth's
      // deviation, the largest in the footprint), with 10 micrometres of margin for the voxel
      // loop's own rounding (its depths are floats: 1e-6 m at 10 m).
      const double reach =
          options_.truncation +
          options_.behind_band_sigmas *
              DepthDeviation(deepest, options_.disparity_noise, camera_.fx * camera_.baseline);
      if (deepest + 1e-5 < near - reach) continue;
      tile = ((v0 + v1) / 2) * tiles_x + (u0 + u1) / 2;
    }
    candidates.push_back({tile, buffer_index, block});
  }
  std::sort(candidates.begin(), candidates.end(), [](const Candidate& a, const Candidate& b) {
    return a.tile != b.tile ? a.tile < b.tile : a.buffer_index < b.buffer_index;
  });
  std::vector<std::pair<Eigen::Vector3i, int>> visible;
  visible.reserve(candidates.size());
  for (const Candidate& candidate : candidates)
    visible.emplace_back(candidate.block, candidate.buffer_index);
  return visible;
}

void DepthFusion::UpdateBlock(const ViewData& view, const Eigen::Vector3i& block, int buffer_index,
                              double sign) const {
  const int resolution = options_.block_resolution;
  const double voxel = options_.voxel_size;
  const std::size_t first =
      static_cast<std::size_t>(buffer_index) * resolution * resolution * resolution;
  // Open3D's voxel (x, y, z) of block k lies at (k * resolution + (x, y, z)) * voxel_size, and
  // its index within the block is x + resolution * (y + resolution * z).
  const Eigen::Vector3d origin = block.cast<double>() * resolution * voxel;
  const Eigen::Vector3d step = view.R.col(0) * voxel;
  const int cols = view.depth.cols, rows = view.depth.rows;
  const double focal_baseline = camera_.fx * camera_.baseline;
  // Each row of voxels along x in two passes: first every voxel's pixel, without a branch, then
  // the depth reads and updates of the voxels inside the image. The projections no longer wait
  // behind each voxel's depth read and its hard-to-predict tests (three quarters of the voxels
  // visited on MH01 see a pixel without depth): fusion about 15 % less on MH01 and the hall
  // loop, the same meshes (docs/benchmarks.md).
  std::array<int, FusionOptions::kMaxBlockResolution> pixel_u, pixel_v;
  std::array<float, FusionOptions::kMaxBlockResolution> voxel_depth;
  // Along each row in float, four voxels at a time (SSE; -fno-trapping-math lets GCC evaluate
  // every voxel's tests, CMakeLists.txt): in double, one at a time, this pass took half the
  // voxel loop's time. From a start in double, a row's voxels are exact to a micrometre at 10 m
  // and their pixels to 1e-4 px, so a voxel that close to a pixel's edge may take the other
  // pixel: as likely either way, and far below a voxel's 2 cm.
  const float fx = static_cast<float>(camera_.fx), fy = static_cast<float>(camera_.fy);
  const float u_offset = static_cast<float>(camera_.cx + 0.5);
  const float v_offset = static_cast<float>(camera_.cy + 0.5);
  const float width = static_cast<float>(cols), height = static_cast<float>(rows);
  const Eigen::Vector3f step_f = step.cast<float>();
  for (int z = 0; z < resolution; ++z) {
    for (int y = 0; y < resolution; ++y) {
      // The row of voxels along x, in the camera frame: start and step.
      const Eigen::Vector3f start =
          (view.R * (origin + voxel * Eigen::Vector3d(0, y, z)) + view.t).cast<float>();
      for (int x = 0; x < resolution; ++x) {
        const float p_x = start.x() + static_cast<float>(x) * step_f.x();
        const float p_y = start.y() + static_cast<float>(x) * step_f.y();
        const float p_z = start.z() + static_cast<float>(x) * step_f.z();
        const float inverse_z = 1.0f / std::max(p_z, 1e-3f);
        // Nearest pixel (floor of +0.5); the range check comes before the cast, which is
        // defined only in range.
        const float u_real = fx * p_x * inverse_z + u_offset;
        const float v_real = fy * p_y * inverse_z + v_offset;
        const bool inside = (p_z > 1e-3f) & (u_real >= 0.0f) & (v_real >= 0.0f) & (u_real < width) &
                            (v_real < height);
        pixel_u[static_cast<std::size_t>(x)] = static_cast<int>(inside ? u_real : -1.0f);
        pixel_v[static_cast<std::size_t>(x)] = static_cast<int>(inside ? v_real : 0.0f);
        voxel_depth[static_cast<std::size_t>(x)] = p_z;
      }
      for (int x = 0; x < resolution; ++x) {
        const int u = pixel_u[static_cast<std::size_t>(x)];
        if (u < 0) continue;
        const int v = pixel_v[static_cast<std::size_t>(x)];
        const float* sample = view.depth_and_ray + 2 * (static_cast<std::size_t>(v) * cols + u);
        const double measured = sample[0];
        if (!(measured > 0.0)) continue;
        // Signed distance along the ray, positive in front of the surface; truncated; nothing
        // farther behind than the band and behind_band_sigmas deviations (unseen). Depth to
        // distance along the pixel's ray: its length per unit depth. Each measurement weighs
        // by its inverse variance.
        const double depth_of_voxel = voxel_depth[static_cast<std::size_t>(x)];
        const double distance = (measured - depth_of_voxel) * sample[1];
        const double sigma = DepthDeviation(measured, options_.disparity_noise, focal_baseline);
        if (distance < -(options_.truncation + options_.behind_band_sigmas * sigma)) continue;
        // In front beyond the band but within front_uncertain_sigmas deviations: the surface
        // may be here, as likely as it may be as far behind, where the band stops; left alone.
        if (distance > options_.truncation && distance < options_.front_uncertain_sigmas * sigma)
          continue;
        const double tsdf = std::clamp(distance / options_.truncation, -1.0, 1.0);
        const double weight = sign / (sigma * sigma);
        const std::size_t cell =
            first + static_cast<std::size_t>(x + resolution * (y + resolution * z));
        float& stored_tsdf = view.tsdf[cell];
        float& stored_weight = view.weight[cell];
        std::uint8_t& stored_grey = view.grey_levels[cell];
        const double total = stored_weight + weight;
        // All of it taken out again: the stored weight is a float, so what is left is
        // rounding, not an observation (relative to the weight taken out).
        if (total <= 1e-4 * std::abs(weight)) {
          stored_tsdf = 0.0f;
          stored_weight = 0.0f;
          stored_grey = 0;
          continue;
        }
        const double g = view.grey.ptr<std::uint8_t>(v)[u];
        stored_tsdf = static_cast<float>((stored_tsdf * stored_weight + tsdf * weight) / total);
        const double mean_grey = (stored_grey * stored_weight + g * weight) / total;
        stored_grey = static_cast<std::uint8_t>(
            std::clamp(RoundHalfAwayFromZero(std::clamp(mean_grey, -1.0, 256.0)), 0L, 255L));
        stored_weight = static_cast<float>(total);
      }
    }
  }
}

namespace {

// Eigen copies of an Open3D (N, 3) tensor's rows, whatever its element type.
template <typename Scalar, typename Vector>
std::vector<Vector> Rows(const o3c::Tensor& tensor) {
  const o3c::Tensor converted = tensor.To(o3c::Dtype::FromType<Scalar>()).Contiguous();
  const Scalar* data = converted.GetDataPtr<Scalar>();
  std::vector<Vector> rows(static_cast<std::size_t>(tensor.GetLength()));
  for (std::size_t i = 0; i < rows.size(); ++i)
    rows[i] = Vector(data[3 * i], data[3 * i + 1], data[3 * i + 2]);
  return rows;
}

}  // namespace

std::vector<float> DepthFusion::GreyAt(const std::vector<Eigen::Vector3d>& points) const {
  // The grey level of the voxel nearest each point (0-1).
  const int resolution = options_.block_resolution;
  std::vector<Eigen::Vector3i> blocks, voxels;
  blocks.reserve(points.size());
  voxels.reserve(points.size());
  for (const Eigen::Vector3d& point : points) {
    const Eigen::Vector3i voxel = (point / options_.voxel_size).array().round().cast<int>();
    const Eigen::Vector3i block = (voxel.cast<double>() / resolution).array().floor().cast<int>();
    blocks.push_back(block);
    voxels.push_back(voxel - block * resolution);
  }
  std::vector<float> grey(points.size(), 0.0f);
  if (points.empty()) return grey;
  o3c::HashMap map = volume_->map();
  o3c::Tensor buffer_indices, found;
  map.Find(BlockKeys(blocks), buffer_indices, found);
  const int* index = buffer_indices.GetDataPtr<int>();
  const bool* is_found = found.GetDataPtr<bool>();
  const std::uint8_t* levels = map.GetValueTensors()[2].GetDataPtr<std::uint8_t>();
  for (std::size_t i = 0; i < points.size(); ++i) {
    if (!is_found[i]) continue;
    const Eigen::Vector3i& v = voxels[i];
    const std::size_t cell =
        static_cast<std::size_t>(index[i]) * resolution * resolution * resolution +
        static_cast<std::size_t>(v.x() + resolution * (v.y() + resolution * v.z()));
    grey[i] = levels[cell] / 255.0f;
  }
  return grey;
}

namespace {

// The summed inverse variance a voxel needs for its distance's standard deviation to be at most
// `max_sigma`.
float WeightThreshold(double max_sigma) {
  return static_cast<float>(1.0 / (max_sigma * max_sigma));
}

}  // namespace

namespace {

// Open3D 0.16 throws from its extraction when the surface is empty (it sets an empty colour
// tensor on the result); that case is an empty surface here, anything else stays an error.
template <typename Extraction>
auto EmptyIfNoSurface(Extraction extract) -> decltype(extract()) {
  try {
    return extract();
  } catch (const std::runtime_error& error) {
    if (std::string(error.what()).find("Colors") == std::string::npos) throw;
    return {};
  }
}

}  // namespace

Mesh DepthFusion::ExtractMesh() const { return ExtractMesh(options_.max_surface_sigma); }

Cloud DepthFusion::ExtractCloud() const { return ExtractCloud(options_.max_surface_sigma); }

Mesh DepthFusion::ExtractMesh(double max_surface_sigma) const {
  Mesh mesh;
  if (volume_->map().Size() == 0) return mesh;
  // Open3D 0.16's marching cubes asserts that the far end of a vertex's edge has a linear index
  // above 0, but the first voxel of the block in buffer 0 has index 0 (and an assertion in
  // Debian's build aborts the process: it did in the DenseMapper on MH01). A cube with a corner
  // of no weight gets no vertices, so that voxel is made weightless during the extraction and
  // given back afterwards.
  o3c::HashMap map = volume_->map();
  float* weights = map.GetValueTensors()[1].GetDataPtr<float>();
  const float first_weight = weights[0];
  weights[0] = 0.0f;
  const auto extract = [&] {
    return volume_->grid.ExtractTriangleMesh(WeightThreshold(max_surface_sigma));
  };
  open3d::t::geometry::TriangleMesh extracted;
  try {
    extracted = EmptyIfNoSurface(extract);
  } catch (...) {
    weights[0] = first_weight;
    throw;
  }
  weights[0] = first_weight;
  if (!extracted.HasVertexPositions() || extracted.GetVertexPositions().GetLength() == 0)
    return mesh;
  mesh.vertices = Rows<double, Eigen::Vector3d>(extracted.GetVertexPositions());
  if (extracted.HasTriangleIndices())
    mesh.triangles = Rows<int, Eigen::Vector3i>(extracted.GetTriangleIndices());
  mesh.grey = GreyAt(mesh.vertices);
  return mesh;
}

Cloud DepthFusion::ExtractCloud(double max_surface_sigma) const {
  Cloud cloud;
  if (volume_->map().Size() == 0) return cloud;
  const open3d::t::geometry::PointCloud extracted = EmptyIfNoSurface(
      [&] { return volume_->grid.ExtractPointCloud(WeightThreshold(max_surface_sigma)); });
  if (!extracted.HasPointPositions() || extracted.GetPointPositions().GetLength() == 0)
    return cloud;
  cloud.points = Rows<double, Eigen::Vector3d>(extracted.GetPointPositions());
  if (extracted.HasPointNormals())
    cloud.normals = Rows<double, Eigen::Vector3d>(extracted.GetPointNormals());
  cloud.grey = GreyAt(cloud.points);
  return cloud;
}

std::size_t DepthFusion::blocks() const { return static_cast<std::size_t>(volume_->map().Size()); }

std::size_t DepthFusion::memory_bytes() const {
  // The hash map keeps room for its capacity's blocks (it doubles when full), each with every
  // voxel's distance, weight and grey level, and its key.
  return static_cast<std::size_t>(volume_->map().GetCapacity()) *
         (VoxelsPerBlock() * kBytesPerVoxel + 3 * sizeof(int));
}

}  // namespace stereo_fabmap_slam::dense
