#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include <Eigen/Geometry>

#include "stereo_fabmap_slam/geometry/stereo_camera.h"
#include "stereo_fabmap_slam/io/option_reader.h"

namespace stereo_fabmap_slam::geometry {

// Minimal solvers for the RANSAC hypotheses: OpenCV's PnP kernels (2-D-3-D), or a 3-D-3-D
// Umeyama fit that uses the stereo depth of the current frame.
enum class PnpKernel { kIterative, kEpnp, kAp3p, kP3p, kSqpnp, kUmeyama };
inline constexpr io::EnumName<PnpKernel> kPnpKernelNames[] = {
    {PnpKernel::kIterative, "ITERATIVE"}, {PnpKernel::kEpnp, "EPNP"},
    {PnpKernel::kAp3p, "AP3P"},           {PnpKernel::kP3p, "P3P"},
    {PnpKernel::kSqpnp, "SQPNP"},         {PnpKernel::kUmeyama, "UMEYAMA"}};

std::optional<PnpKernel> ParsePnpKernel(const std::string& name);  // "ITERATIVE", "EPNP", ...
std::string PnpKernelNames();                                      // for error messages

struct PnpCorrespondence {
  Eigen::Vector3d world;                  // map point
  Eigen::Vector2d pixel;                  // rectified left image
  bool has_depth = false;                 // stereo point of the current frame available
  Eigen::Vector3d camera_point{0, 0, 0};  // that stereo point, in the camera frame
};

struct PnpRansacOptions {
  PnpKernel kernel = PnpKernel::kAp3p;
  double reprojection_threshold = 2.0;  // [px] inlier limit
  int max_iterations = 100;
  double confidence = 0.999;
  std::uint64_t seed = 1;  // Umeyama kernel's sampling (OpenCV's RANSAC seeds itself)
};

struct PnpResult {
  bool success = false;
  Eigen::Isometry3d T_camera_world = Eigen::Isometry3d::Identity();
  std::vector<int> inliers;  // indices into the correspondences
};

// Robust camera pose from correspondences. `guess` (T_camera_world) seeds the iterative kernel.
PnpResult SolvePnpRansac(const std::vector<PnpCorrespondence>& correspondences,
                         const geometry::StereoCamera& camera, const PnpRansacOptions& options,
                         const Eigen::Isometry3d& guess);

}  // namespace stereo_fabmap_slam::geometry
