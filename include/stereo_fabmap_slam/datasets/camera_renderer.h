#pragma once

#include <vector>

#include <Eigen/Geometry>
#include <opencv2/core.hpp>

#include "stereo_fabmap_slam/camera/camera_calibration.h"
#include "stereo_fabmap_slam/datasets/hall_scene.h"

namespace stereo_fabmap_slam::datasets {

// Renders what one raw camera sees: for every pixel, the ray that the camera's own
// radial-tangential distortion model maps to it (precomputed once with OpenCV's undistortion),
// traced through the scene. So a point projected with the same calibration (cv::projectPoints)
// lands where the renderer drew it.
class CameraRenderer {
 public:
  explicit CameraRenderer(const camera::CameraCalibration& camera);

  // Grey levels as CV_32F, before noise and exposure. With `parallel`, rows are rendered on
  // OpenCV's threads; either way the result is the same (each pixel depends only on its ray).
  cv::Mat Render(const HallScene& scene, const Eigen::Isometry3d& T_world_camera,
                 bool parallel = true) const;

 private:
  // The rays of a square of kTileSize x kTileSize pixels lie within `half_angle` of `axis`
  // (camera frame): only the obstacles in that cone need tracing for them.
  struct Tile {
    Eigen::Vector3f axis;
    float half_angle;
  };
  static constexpr int kTileSize = 16;

  const Eigen::Vector3f& Ray(int u, int v) const {
    return rays_[static_cast<std::size_t>(v) * size_.width + u];
  }

  cv::Size size_;
  std::vector<Eigen::Vector3f> rays_;  // unit directions in the camera frame, row-major
  int tile_columns_;
  std::vector<Tile> tiles_;  // row-major
  float pixel_angle_;
};

}  // namespace stereo_fabmap_slam::datasets
