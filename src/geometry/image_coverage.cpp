#include "stereo_fabmap_slam/geometry/image_coverage.h"

#include <algorithm>

namespace stereo_fabmap_slam::geometry {

int OccupiedCells(const std::vector<Eigen::Vector2d>& pixels, const cv::Size& size, int grid) {
  std::vector<char> occupied(static_cast<std::size_t>(grid * grid), 0);
  for (const Eigen::Vector2d& pixel : pixels) {
    const int column = std::clamp(static_cast<int>(pixel.x() * grid / size.width), 0, grid - 1);
    const int row = std::clamp(static_cast<int>(pixel.y() * grid / size.height), 0, grid - 1);
    occupied[static_cast<std::size_t>(row * grid + column)] = 1;
  }
  return static_cast<int>(std::count(occupied.begin(), occupied.end(), 1));
}

}  // namespace stereo_fabmap_slam::geometry
