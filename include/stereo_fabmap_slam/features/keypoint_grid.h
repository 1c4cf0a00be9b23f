#pragma once

#include <algorithm>
#include <cstddef>
#include <vector>

#include <opencv2/core.hpp>

namespace stereo_fabmap_slam::features {

// Key points of a frame binned in square cells, for radius searches (search by projection).
// Keeps a reference to the key points: they must outlive the grid.
class KeypointGrid {
 public:
  KeypointGrid(const std::vector<cv::KeyPoint>& keypoints, const cv::Size& size, int cell)
      : cell_(cell),
        columns_(size.width / cell + 1),
        rows_(size.height / cell + 1),
        cells_(static_cast<std::size_t>(columns_ * rows_)),
        keypoints_(keypoints) {
    for (int i = 0; i < static_cast<int>(keypoints.size()); ++i) {
      cells_[Index(keypoints[i].pt.x, keypoints[i].pt.y)].push_back(i);
    }
  }

  // Calls visit(i) for every key point i within `radius` pixels of (u, v).
  template <typename Visit>
  void ForEachWithin(double u, double v, double radius, Visit visit) const {
    const int c0 = std::max(0, static_cast<int>((u - radius) / cell_));
    const int c1 = std::min(columns_ - 1, static_cast<int>((u + radius) / cell_));
    const int r0 = std::max(0, static_cast<int>((v - radius) / cell_));
    const int r1 = std::min(rows_ - 1, static_cast<int>((v + radius) / cell_));
    const double radius2 = radius * radius;
    for (int r = r0; r <= r1; ++r) {
      for (int c = c0; c <= c1; ++c) {
        for (const int i : cells_[static_cast<std::size_t>(r * columns_ + c)]) {
          const double du = keypoints_[i].pt.x - u, dv = keypoints_[i].pt.y - v;
          if (du * du + dv * dv <= radius2) visit(i);
        }
      }
    }
  }

 private:
  std::size_t Index(double u, double v) const {
    const int c = std::clamp(static_cast<int>(u / cell_), 0, columns_ - 1);
    const int r = std::clamp(static_cast<int>(v / cell_), 0, rows_ - 1);
    return static_cast<std::size_t>(r * columns_ + c);
  }

  int cell_, columns_, rows_;
  std::vector<std::vector<int>> cells_;
  const std::vector<cv::KeyPoint>& keypoints_;
};

}  // namespace stereo_fabmap_slam::features
