#pragma once

#include <algorithm>
#include <cstddef>
#include <vector>

#include <opencv2/core.hpp>

namespace stereo_fabmap_slam::features {

// Key points of a frame binned in square cells, for radius searches (search by projection).
// Keeps a reference to the key points: they must outlive the grid. The cells are one array
// sorted by counting, not a vector per cell: a frame's grid would otherwise cost a thousand
// small allocations, and over a long run the fragmented heap made them slower and slower
// (docs/benchmarks.md).
class KeypointGrid {
 public:
  KeypointGrid(const std::vector<cv::KeyPoint>& keypoints, const cv::Size& size, int cell)
      : cell_(cell),
        columns_(size.width / cell + 1),
        rows_(size.height / cell + 1),
        cell_start_(static_cast<std::size_t>(columns_ * rows_) + 1, 0),
        in_cells_(keypoints.size()),
        keypoints_(keypoints) {
    for (const cv::KeyPoint& keypoint : keypoints) {
      ++cell_start_[Index(keypoint.pt.x, keypoint.pt.y) + 1];
    }
    for (std::size_t c = 1; c < cell_start_.size(); ++c) cell_start_[c] += cell_start_[c - 1];
    std::vector<int> next(cell_start_.begin(), cell_start_.end() - 1);
    for (int i = 0; i < static_cast<int>(keypoints.size()); ++i) {
      in_cells_[static_cast<std::size_t>(next[Index(keypoints[i].pt.x, keypoints[i].pt.y)]++)] = i;
    }
  }

  // Calls visit(i) for every key point i within `radius` pixels of (u, v), cell by cell, in key
  // point order within a cell.
  template <typename Visit>
  void ForEachWithin(double u, double v, double radius, Visit visit) const {
    const int c0 = std::max(0, static_cast<int>((u - radius) / cell_));
    const int c1 = std::min(columns_ - 1, static_cast<int>((u + radius) / cell_));
    const int r0 = std::max(0, static_cast<int>((v - radius) / cell_));
    const int r1 = std::min(rows_ - 1, static_cast<int>((v + radius) / cell_));
    const double radius2 = radius * radius;
    for (int r = r0; r <= r1; ++r) {
      for (int c = c0; c <= c1; ++c) {
        const std::size_t cell = static_cast<std::size_t>(r * columns_ + c);
        for (int k = cell_start_[cell]; k < cell_start_[cell + 1]; ++k) {
          const int i = in_cells_[static_cast<std::size_t>(k)];
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
  std::vector<int> cell_start_;  // cell c's key points: in_cells_[cell_start_[c] ...]
  std::vector<int> in_cells_;    // up to cell_start_[c + 1]
  const std::vector<cv::KeyPoint>& keypoints_;
};

}  // namespace stereo_fabmap_slam::features
