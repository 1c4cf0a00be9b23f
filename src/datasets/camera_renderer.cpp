#include "stereo_fabmap_slam/datasets/camera_renderer.h"

#include <algorithm>
#include <cmath>

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

  tile_columns_ = (size_.width + kTileSize - 1) / kTileSize;
  const int tile_rows = (size_.height + kTileSize - 1) / kTileSize;
  for (int tile_v = 0; tile_v < tile_rows; ++tile_v) {
    for (int tile_u = 0; tile_u < tile_columns_; ++tile_u) {
      const cv::Rect pixels =
          cv::Rect(tile_u * kTileSize, tile_v * kTileSize, kTileSize, kTileSize) &
          cv::Rect(cv::Point(0, 0), size_);
      Eigen::Vector3d sum = Eigen::Vector3d::Zero();
      for (int v = pixels.y; v < pixels.br().y; ++v) {
        for (int u = pixels.x; u < pixels.br().x; ++u) sum += Ray(u, v).cast<double>();
      }
      const Eigen::Vector3d axis = sum.normalized();
      double half_angle = 0;
      for (int v = pixels.y; v < pixels.br().y; ++v) {
        for (int u = pixels.x; u < pixels.br().x; ++u) {
          half_angle =
              std::max(half_angle, std::acos(std::min(1.0, axis.dot(Ray(u, v).cast<double>()))));
        }
      }
      tiles_.push_back({axis.cast<float>(), static_cast<float>(half_angle)});
    }
  }
}

cv::Mat CameraRenderer::Render(const HallScene& scene, const Eigen::Isometry3d& T_world_camera,
                               bool parallel) const {
  cv::Mat image(size_, CV_32F);
  const Eigen::Matrix3f rotation = T_world_camera.linear().cast<float>();
  const Eigen::Vector3f origin = T_world_camera.translation().cast<float>();
  // Band by band of tiles; each tile traces only the obstacles its rays may hit, with the same
  // result as tracing all (byte-identical images). Most tiles see one or none of the dozen:
  // 10 s of the loop route render in 14.3 instead of 18.5 s of CPU (docs/benchmarks.md).
  const auto render_bands = [&](const cv::Range& bands) {
    for (int band = bands.start; band < bands.end; ++band) {
      const int row_end = std::min(size_.height, (band + 1) * kTileSize);
      for (int tile_u = 0; tile_u < tile_columns_; ++tile_u) {
        const Tile& tile = tiles_[static_cast<std::size_t>(band * tile_columns_ + tile_u)];
        const std::vector<int> obstacles =
            scene.ObstaclesInCone(origin, rotation * tile.axis, tile.half_angle);
        const int column_end = std::min(size_.width, (tile_u + 1) * kTileSize);
        for (int v = band * kTileSize; v < row_end; ++v) {
          float* out = image.ptr<float>(v);
          for (int u = tile_u * kTileSize; u < column_end; ++u) {
            out[u] = scene.Trace(origin, rotation * Ray(u, v), pixel_angle_, &obstacles);
          }
        }
      }
    }
  };
  const cv::Range bands(0, static_cast<int>(tiles_.size()) / tile_columns_);
  if (parallel) {
    cv::parallel_for_(bands, render_bands);
  } else {
    render_bands(bands);
  }
  return image;
}

}  // namespace stereo_fabmap_slam::datasets
