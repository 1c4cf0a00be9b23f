#pragma once

#include <cstddef>
#include <cstdint>
#include <map>
#include <vector>

#include <Eigen/Geometry>
#include <opencv2/core.hpp>

#include "stereo_fabmap_slam/dense/dense_options.h"
#include "stereo_fabmap_slam/dense/depth_fusion.h"
#include "stereo_fabmap_slam/dense/stereo_depth.h"
#include "stereo_fabmap_slam/dense/view_facing_surface.h"
#include "stereo_fabmap_slam/geometry/stereo_camera.h"

namespace stereo_fabmap_slam::dense {

// The dense map of a keyframe map: each keyframe's stereo depth fused at its map pose, and kept
// (grey image and depth, 3 bytes a pixel, and the blocks it updated) so that when loop closing
// moves the keyframe its depth is taken out at the old pose and put back at the new one. What the
// dense mapping stage (DenseMappingStage) fuses into. Not thread-safe.
class KeyframeVolume {
 public:
  struct Timing {
    double depth_ms = 0;   // stereo matching
    double fusion_ms = 0;  // integration into the volume
  };

  // Throws std::invalid_argument for invalid options.
  KeyframeVolume(const StereoDepthOptions& depth_options, const FusionOptions& fusion_options,
                 const geometry::StereoCamera& camera);

  // The keyframe's rectified pair, its depth fused at `T_map_camera` (the rectified left camera
  // in the map). A keyframe added before is left as it is (false).
  bool Add(std::uint64_t id, const cv::Mat& left, const cv::Mat& right,
           const Eigen::Isometry3d& T_map_camera, Timing* timing = nullptr);
  // Every keyframe of `poses` whose pose moved so far that its surface would shift by half
  // a voxel at the depth limit is taken out at its old pose and put back at the new one, those
  // that moved most first, at most `max_keyframes` of them; keyframes `poses` lacks stay.
  // Returns how many moved; call again with the same poses for the rest (Moving() says how many
  // are left).
  std::size_t Move(const std::map<std::uint64_t, Eigen::Isometry3d>& poses,
                   std::size_t max_keyframes = static_cast<std::size_t>(-1));
  std::size_t Moving(const std::map<std::uint64_t, Eigen::Isometry3d>& poses) const;

  // The fused surface where some keyframe saw it from the side it faces (ViewFacingSurface:
  // marching cubes also meshes the back of the band behind a wall, facing away from them all).
  Mesh ExtractMesh() const;
  Cloud ExtractCloud() const;
  const DepthFusion& fusion() const { return fusion_; }
  std::size_t keyframes() const { return kept_.size(); }
  // The volume's and the kept images' memory [bytes].
  std::size_t memory_bytes() const;

 private:
  struct Kept {
    cv::Mat grey;      // CV_8U, the rectified left image
    cv::Mat depth_mm;  // CV_16U [mm]: what was integrated (0.5 mm of rounding, far below the noise)
    Eigen::Isometry3d T_map_camera;
    std::vector<Eigen::Vector3i> blocks;  // those its integration updated (12 bytes each)
  };
  // How far a keyframe's surface shifts at the depth limit [m] between two poses.
  double Shift(const Eigen::Isometry3d& from, const Eigen::Isometry3d& to) const;
  ViewFacingSurface FacingKeyframes() const;

  StereoDepth stereo_;
  DepthFusion fusion_;
  geometry::StereoCamera camera_;
  double voxel_size_, max_depth_, truncation_;
  std::map<std::uint64_t, Kept> kept_;
};

}  // namespace stereo_fabmap_slam::dense
