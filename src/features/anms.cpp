#include "stereo_fabmap_slam/features/anms.h"

#include <algorithm>
#include <cmath>

namespace stereo_fabmap_slam::features {
namespace {

void SortByResponse(std::vector<cv::KeyPoint>* keypoints) {
  // Stable, with position as the tie-break, so that the selection is deterministic.
  std::stable_sort(keypoints->begin(), keypoints->end(),
                   [](const cv::KeyPoint& a, const cv::KeyPoint& b) {
                     if (a.response != b.response) return a.response > b.response;
                     if (a.pt.y != b.pt.y) return a.pt.y < b.pt.y;
                     return a.pt.x < b.pt.x;
                   });
}

// Indices kept when each kept point covers a square of side `width` around it.
std::vector<int> Cover(const std::vector<cv::KeyPoint>& sorted, const cv::Size& size, int width) {
  const double cell = std::max(1.0, width / 2.0);
  const int columns = static_cast<int>(std::ceil(size.width / cell)) + 1;
  const int rows = static_cast<int>(std::ceil(size.height / cell)) + 1;
  const int reach = static_cast<int>(std::floor(width / cell));
  std::vector<unsigned char> covered(static_cast<std::size_t>(columns) * rows, 0);
  std::vector<int> kept;
  for (int i = 0; i < static_cast<int>(sorted.size()); ++i) {
    const int row = std::clamp(static_cast<int>(sorted[i].pt.y / cell), 0, rows - 1);
    const int column = std::clamp(static_cast<int>(sorted[i].pt.x / cell), 0, columns - 1);
    if (covered[static_cast<std::size_t>(row) * columns + column]) continue;
    kept.push_back(i);
    for (int r = std::max(0, row - reach); r <= std::min(rows - 1, row + reach); ++r) {
      for (int c = std::max(0, column - reach); c <= std::min(columns - 1, column + reach); ++c) {
        covered[static_cast<std::size_t>(r) * columns + c] = 1;
      }
    }
  }
  return kept;
}

}  // namespace

std::vector<cv::KeyPoint> SelectStrongest(std::vector<cv::KeyPoint> keypoints, int count) {
  SortByResponse(&keypoints);
  if (static_cast<int>(keypoints.size()) > count) keypoints.resize(static_cast<std::size_t>(count));
  return keypoints;
}

std::vector<cv::KeyPoint> SelectWithAnms(std::vector<cv::KeyPoint> keypoints, int count,
                                         const cv::Size& image_size, double tolerance) {
  SortByResponse(&keypoints);
  if (static_cast<int>(keypoints.size()) <= count) return keypoints;
  // Square side for `count` points spread evenly over the image, then binary search around it.
  const int lower_count = static_cast<int>(count * (1.0 - tolerance));
  const int upper_count = static_cast<int>(count * (1.0 + tolerance));
  int low = 1;
  int high = std::max(image_size.width, image_size.height);
  std::vector<int> best;
  while (low <= high) {
    const int width = (low + high) / 2;
    std::vector<int> kept = Cover(keypoints, image_size, width);
    const int n = static_cast<int>(kept.size());
    if (best.empty() || std::abs(n - count) < std::abs(static_cast<int>(best.size()) - count)) {
      best = kept;
    }
    if (n >= lower_count && n <= upper_count) break;
    if (n > count) {
      low = width + 1;  // too many: cover more
    } else {
      high = width - 1;
    }
  }
  std::vector<cv::KeyPoint> selected;
  selected.reserve(std::min<std::size_t>(best.size(), count));
  for (const int index : best) {
    if (static_cast<int>(selected.size()) == count) break;
    selected.push_back(keypoints[static_cast<std::size_t>(index)]);
  }
  return selected;
}

}  // namespace stereo_fabmap_slam::features
