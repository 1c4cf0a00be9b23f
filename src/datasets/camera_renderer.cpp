#include "stereo_fabmap_slam/datasets/camera_renderer.h"

#include <opencv2/calib3d.hpp>
#include <opencv2/core/utility.hpp>

namespace stereo_fabmap_slam::datasets {

CameraRenderer::CameraRenderer(const camera::CameraCalibration& camera)
    : size_(camera.resolution), pixel_angle_(static_cast<float>(1.0 / camera.fx)) {
  std::vector<cv::Point2d> pixels, normalised;
  pixels.reserve(static_cast<std::size_t>(size_.area()));
  for (int v = 0; v < size_.height; ++v) {
    for (int u = 0; u < size_.width; ++u) pixels.emplace_back(u, v);
  }
  // Iterate the undistortion to convergence: the default 5 iterations leave sub-pixel errors
  // at the corners of a strongly distorted lens.
  cv::undistortPoints(
      pixels, normalised, camera.CameraMatrix(), camera.distortion, cv::noArray(), cv::noArray(),
      cv::TermCriteria(cv::TermCriteria::COUNT | cv::TermCriteria::EPS, 100, 1e-12));
  rays_.reserve(normalised.size());
  for (const cv::Point2d& p : normalised)
    rays_.push_back(Eigen::Vector3f(p.x, p.y, 1.0f).normalized());
}

cv::Mat CameraRenderer::Render(const HallScene& scene, const Eigen::Isometry3d& T_world_camera,
                               bool parallel) const {
  cv::Mat image(size_, CV_32F);
  const Eigen::Matrix3f rotation = T_world_camera.linear().cast<float>();
  const Eigen::Vector3f origin = T_world_camera.translation().cast<float>();
  const std::vector<int> obstacles = scene.ObstaclesInFront(rotation.transpose(), origin);
  const auto render_rows = [&](const cv::Range& rows) {
    for (int v = rows.start; v < rows.end; ++v) {
      float* out = image.ptr<float>(v);
      const Eigen::Vector3f* ray = &rays_[static_cast<std::size_t>(v) * size_.width];
      for (int u = 0; u < size_.width; ++u) {
        out[u] = scene.Trace(origin, rotation * ray[u], pixel_angle_, &obstacles);
      }
    }
  };
  if (parallel) {
    cv::parallel_for_(cv::Range(0, size_.height), render_rows);
  } else {
    render_rows(cv::Range(0, size_.height));
  }
  return image;
}

}  // namespace stereo_fabmap_slam::datasets
