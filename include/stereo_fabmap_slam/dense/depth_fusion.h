#pragma once

#include <cstddef>
#include <memory>
#include <vector>

#include <Eigen/Geometry>
#include <opencv2/core.hpp>

#include "stereo_fabmap_slam/dense/dense_options.h"
#include "stereo_fabmap_slam/geometry/stereo_camera.h"

namespace open3d::pipelines::integration {
class ScalableTSDFVolume;
class UniformTSDFVolume;
}  // namespace open3d::pipelines::integration

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
// (Open3D's ScalableTSDFVolume, grey levels as colour), and the surface taken out of it as a
// triangle mesh or a point cloud. Open3D stays behind this class: its headers and compile
// definitions do not reach the code that uses it. Not thread-safe.
class DepthFusion {
 public:
  // Throws std::invalid_argument for invalid options.
  DepthFusion(const FusionOptions& options, const geometry::StereoCamera& camera);
  ~DepthFusion();
  DepthFusion(const DepthFusion&) = delete;
  DepthFusion& operator=(const DepthFusion&) = delete;

  // `grey`: the rectified left image (8-bit); `depth`: metres along the optical axis (CV_32F,
  // 0 where unknown), both of the camera's size; `T_world_camera`: where the camera was.
  // Each measurement weighs by its inverse variance (1 / depth^4: stereo's depth error grows
  // with the square of the depth). Open3D's own integration weighs every pixel alike, so the
  // update is written here, into Open3D's blocks, whose marching cubes make the mesh.
  void Integrate(const cv::Mat& grey, const cv::Mat& depth,
                 const Eigen::Isometry3d& T_world_camera);
  // Takes a view integrated before out again (the same images and pose): what a keyframe whose
  // pose loop closing moved needs before it is integrated at its new pose. Open3D has none.
  void Deintegrate(const cv::Mat& grey, const cv::Mat& depth,
                   const Eigen::Isometry3d& T_world_camera);
  void Reset();

  Mesh ExtractMesh() const;    // marching cubes over the allocated blocks
  Cloud ExtractCloud() const;  // the zero crossings of the signed distance, with normals
  // Blocks of voxels allocated so far, and their memory [bytes]: what grows with the surface.
  std::size_t blocks() const;
  std::size_t memory_bytes() const;

 private:
  std::vector<Eigen::Vector3i> BlocksNearSurface(const cv::Mat& depth,
                                                 const Eigen::Isometry3d& T_world_camera) const;
  void Fuse(const cv::Mat& grey, const cv::Mat& depth, const Eigen::Isometry3d& T_world_camera,
            double sign);
  // One block's voxels updated by one view (`R`, `t`: world to camera; `sign` -1 takes out).
  void UpdateBlock(const cv::Mat& grey, const cv::Mat& depth, const Eigen::Matrix3d& R,
                   const Eigen::Vector3d& t, double sign,
                   open3d::pipelines::integration::UniformTSDFVolume* block) const;

  FusionOptions options_;
  geometry::StereoCamera camera_;
  std::unique_ptr<open3d::pipelines::integration::ScalableTSDFVolume> volume_;
};

}  // namespace stereo_fabmap_slam::dense
