#pragma once

#include <cstddef>
#include <cstdint>
#include <memory>
#include <utility>
#include <vector>

#include <Eigen/Geometry>
#include <opencv2/core.hpp>

#include "stereo_fabmap_slam/dense/dense_options.h"
#include "stereo_fabmap_slam/geometry/stereo_camera.h"

namespace open3d::core {
class HashMap;
}  // namespace open3d::core

namespace stereo_fabmap_slam::dense {

// A surface taken out of the volume, in the world frame of the poses, with the fused grey level
// (0-1) of every vertex or point.
struct Mesh {
  std::vector<Eigen::Vector3d> vertices;
  std::vector<Eigen::Vector3i> triangles;  // indices into vertices, counter-clockwise outside
  std::vector<float> grey;                 // per vertex
};
struct Cloud {
  std::vector<Eigen::Vector3d> points;
  std::vector<Eigen::Vector3d> normals;
  std::vector<float> grey;
};

// Depth images of the rectified left camera fused into one truncated signed distance volume
// (Open3D's voxel block grid: a hash map of blocks, allocated where surfaces are), and the
// surface taken out of it as a triangle mesh or a point cloud. Open3D stays behind this class:
// its headers and compile definitions do not reach the code that uses it. Not thread-safe.
class DepthFusion {
 public:
  // Throws std::invalid_argument for invalid options.
  DepthFusion(const FusionOptions& options, const geometry::StereoCamera& camera);
  ~DepthFusion();
  DepthFusion(const DepthFusion&) = delete;
  DepthFusion& operator=(const DepthFusion&) = delete;

  // `grey`: the rectified left image (8-bit); `depth`: metres along the optical axis (CV_32F,
  // 0 where unknown), both of the camera's size; `T_world_camera`: where the camera was.
  // Each measurement weighs by its inverse variance (stereo's depth error grows with the square
  // of the depth), and every allocated block the view sees is updated, also far in front of
  // this view's surfaces (free space clears what noisier views put there). Open3D's own
  // integration weighs every pixel alike and touches only the blocks around the view's
  // surfaces, so the update is written here, into Open3D's blocks, whose marching cubes make
  // the mesh. Returns the blocks the view updated, which taking it out again needs.
  std::vector<Eigen::Vector3i> Integrate(const cv::Mat& grey, const cv::Mat& depth,
                                         const Eigen::Isometry3d& T_world_camera);
  // Takes a view integrated before out again (the same images and pose, and the blocks its
  // Integrate returned): what a keyframe whose pose loop closing moved needs before it is
  // integrated at its new pose. Open3D has none. Only those blocks: one allocated later in the
  // view's free space never had the view's update, and taking it out there would corrupt it.
  void Deintegrate(const cv::Mat& grey, const cv::Mat& depth,
                   const Eigen::Isometry3d& T_world_camera,
                   const std::vector<Eigen::Vector3i>& blocks);
  void Reset();

  // Only where the fused distance is known well enough (FusionOptions::max_surface_sigma, or
  // the standard deviation [m] given).
  Mesh ExtractMesh() const;    // marching cubes over the allocated blocks
  Cloud ExtractCloud() const;  // the zero crossings of the signed distance, with normals
  Mesh ExtractMesh(double max_surface_sigma) const;
  Cloud ExtractCloud(double max_surface_sigma) const;
  // Blocks of voxels allocated so far, and their memory [bytes]: what grows with the surface.
  std::size_t blocks() const;
  std::size_t memory_bytes() const;
  const FusionOptions& options() const { return options_; }

 private:
  struct Volume;    // Open3D's grid
  struct ViewData;  // one view's images and pose, as the block update reads them

  std::size_t VoxelsPerBlock() const;  // block_resolution cubed
  // Grows the grid (doubling) if `blocks` more would not fit: Open3D's own growth is slow.
  void MakeRoomFor(std::int64_t blocks);
  std::vector<Eigen::Vector3i> BlocksNearSurface(const cv::Mat& depth,
                                                 const Eigen::Isometry3d& T_world_camera) const;
  // The allocated blocks (and their place in the grid's buffers) whose voxels a view updates.
  std::vector<std::pair<Eigen::Vector3i, int>> VisibleBlocks(
      open3d::core::HashMap& map, const cv::Mat& depth,
      const Eigen::Isometry3d& T_camera_world) const;
  // Integrates (`blocks` null) or takes out (the blocks given) a view; returns the blocks
  // updated.
  std::vector<Eigen::Vector3i> Fuse(const cv::Mat& grey, const cv::Mat& depth,
                                    const Eigen::Isometry3d& T_world_camera,
                                    const std::vector<Eigen::Vector3i>* blocks);
  // One block's voxels updated by one view (`sign` -1 takes it out).
  void UpdateBlock(const ViewData& view, const Eigen::Vector3i& block, int buffer_index,
                   double sign) const;
  std::vector<float> GreyAt(const std::vector<Eigen::Vector3d>& points) const;

  FusionOptions options_;
  geometry::StereoCamera camera_;
  cv::Mat ray_length_;                // CV_32F: each pixel's ray length per unit of depth
  std::vector<float> depth_and_ray_;  // the view being fused: ViewData::depth_and_ray
  std::unique_ptr<Volume> volume_;
};

}  // namespace stereo_fabmap_slam::dense
