#include "stereo_fabmap_slam/features/stereo_matcher.h"

#include "stereo_fabmap_slam/features/feature_factory.h"

#include <cmath>
#include <limits>
#include <stdexcept>

namespace stereo_fabmap_slam::features {

StereoMatcher::StereoMatcher(const StereoMatcherOptions& options,
                             const geometry::StereoCamera& camera, int norm,
                             double max_descriptor_distance, concurrency::HelperThread* helper)
    : options_(options),
      camera_(camera),
      norm_(norm),
      max_descriptor_distance_(max_descriptor_distance),
      helper_(helper) {
  options_.Validate();
}

std::vector<float> StereoMatcher::Match(const cv::Mat& left_image,
                                        const std::vector<cv::KeyPoint>& left,
                                        const cv::Mat& left_descriptors, const cv::Mat& right_image,
                                        const std::vector<cv::KeyPoint>& right,
                                        const cv::Mat& right_descriptors) const {
  // Right key points by image row, so that each left point looks only at its row band: row r's
  // are by_row[row_start[r]] to by_row[row_start[r + 1] - 1], in key point order. Sorted by
  // counting into one array: a vector per row cost a few thousand small allocations a frame,
  // and over a long run the fragmented heap made them slower and slower (docs/benchmarks.md).
  const int rows = right_image.rows;
  const int band = static_cast<int>(std::ceil(options_.max_row_difference));
  const auto row_band = [&](int j) {
    const int row = static_cast<int>(std::lround(right[j].pt.y));
    return std::make_pair(std::max(0, row - band), std::min(rows - 1, row + band));
  };
  std::vector<int> row_start(static_cast<std::size_t>(rows) + 1, 0);
  for (int j = 0; j < static_cast<int>(right.size()); ++j) {
    const auto [first, last] = row_band(j);
    for (int r = first; r <= last; ++r) ++row_start[static_cast<std::size_t>(r) + 1];
  }
  for (int r = 0; r < rows; ++r) row_start[r + 1] += row_start[r];
  std::vector<int> by_row(static_cast<std::size_t>(row_start.back()));
  std::vector<int> next(row_start.begin(), row_start.end() - 1);
  for (int j = 0; j < static_cast<int>(right.size()); ++j) {
    const auto [first, last] = row_band(j);
    for (int r = first; r <= last; ++r) by_row[static_cast<std::size_t>(next[r]++)] = j;
  }
  const double min_disparity = camera_.fx * camera_.baseline / options_.max_depth;
  const double max_disparity =
      std::min(options_.max_disparity, camera_.fx * camera_.baseline / options_.min_depth);

  std::vector<float> u_right(left.size(), -1.0f);
  // Each left key point is matched on its own: pieces on two threads, same result.
  const auto match_range = [&](int begin, int end) {
    std::vector<int> costs;  // RefineColumn's, one allocation for the range
    for (int i = begin; i < end; ++i) {
      const cv::Point2f& p = left[i].pt;
      const int row = std::clamp(static_cast<int>(std::lround(p.y)), 0, rows - 1);
      double best = std::numeric_limits<double>::max(), second = best;
      int best_j = -1;
      const Patch left_patch =
          uses_descriptors()
              ? Patch{}
              : MakePatch(left_image, cv::Point(static_cast<int>(std::lround(p.x)), row));
      for (int k = row_start[row]; k < row_start[row + 1]; ++k) {
        const int j = by_row[static_cast<std::size_t>(k)];
        const cv::Point2f& q = right[j].pt;
        const double disparity = p.x - q.x;
        if (std::abs(q.y - p.y) > options_.max_row_difference || disparity < 0 ||
            disparity > max_disparity + options_.search_radius) {
          continue;
        }
        const double distance =
            uses_descriptors()
                ? DescriptorDistance(left_descriptors, i, right_descriptors, j, norm_)
                : PatchDistance(left_patch, right_image,
                                cv::Point(static_cast<int>(std::lround(q.x)),
                                          static_cast<int>(std::lround(q.y))));
        if (distance < best) {
          second = best;
          best = distance;
          best_j = j;
        } else if (distance < second) {
          second = distance;
        }
      }
      const double limit =
          uses_descriptors() ? max_descriptor_distance_ : options_.max_patch_distance;
      if (best_j < 0 || best > limit || best > options_.ratio * second) continue;
      float column = right[best_j].pt.x;
      if (options_.subpixel) column = RefineColumn(left_image, p, right_image, column, &costs);
      if (column < 0) continue;
      const double disparity = p.x - column;
      if (disparity >= min_disparity && disparity <= max_disparity) u_right[i] = column;
    }
  };
  const int count = static_cast<int>(left.size());
  if (helper_ != nullptr) {
    // Eight pieces: a piece's cost varies with its rows' candidates; more pieces balance the
    // two threads better, at a hand-over of a microsecond each.
    constexpr int kPieces = 8;
    helper_->ForEachPiece(kPieces, [&](int piece) {
      match_range(count * piece / kPieces, count * (piece + 1) / kPieces);
    });
  } else {
    match_range(0, count);
  }
  return u_right;
}

StereoMatcher::Patch StereoMatcher::MakePatch(const cv::Mat& image, const cv::Point& centre) const {
  Patch patch;
  const int r = options_.patch_radius;
  if (centre.x < r || centre.y < r || centre.x >= image.cols - r || centre.y >= image.rows - r) {
    return patch;
  }
  patch.valid = true;
  patch.image = &image;
  patch.centre = centre;
  for (int dy = -r; dy <= r; ++dy) {
    const std::uint8_t* row = image.ptr<std::uint8_t>(centre.y + dy) + centre.x - r;
    for (int dx = 0; dx <= 2 * r; ++dx) {
      patch.sum += row[dx];
      patch.sum_squares += row[dx] * row[dx];
    }
  }
  return patch;
}

double StereoMatcher::PatchDistance(const Patch& left, const cv::Mat& right_image,
                                    const cv::Point& right) const {
  const int r = options_.patch_radius;
  if (!left.valid || right.x < r || right.y < r || right.x >= right_image.cols - r ||
      right.y >= right_image.rows - r) {
    return 2.0;
  }
  // Integer sums: 11x11 patches of 8-bit values cannot overflow 32 bits.
  std::int32_t sum_r = 0, sum_rr = 0, sum_lr = 0;
  for (int dy = -r; dy <= r; ++dy) {
    const std::uint8_t* l = left.image->ptr<std::uint8_t>(left.centre.y + dy) + left.centre.x - r;
    const std::uint8_t* q = right_image.ptr<std::uint8_t>(right.y + dy) + right.x - r;
    for (int dx = 0; dx <= 2 * r; ++dx) {
      sum_r += q[dx];
      sum_rr += q[dx] * q[dx];
      sum_lr += l[dx] * q[dx];
    }
  }
  const double n = (2 * r + 1) * (2 * r + 1);
  const double var_l = left.sum_squares - double(left.sum) * left.sum / n;
  const double var_r = sum_rr - double(sum_r) * sum_r / n;
  if (var_l < n || var_r < n) return 2.0;  // flat patch (std below 1 grey level): no information
  return 1.0 - (sum_lr - double(left.sum) * sum_r / n) / std::sqrt(var_l * var_r);
}

float StereoMatcher::RefineColumn(const cv::Mat& left_image, const cv::Point2f& left_point,
                                  const cv::Mat& right_image, float right_column,
                                  std::vector<int>* costs_buffer) const {
  const int r = options_.patch_radius, search = options_.search_radius;
  const int ul = static_cast<int>(std::lround(left_point.x));
  const int v = static_cast<int>(std::lround(left_point.y));
  const int ur = static_cast<int>(std::lround(right_column));
  if (v - r < 0 || v + r >= left_image.rows || ul - r < 0 || ul + r >= left_image.cols ||
      ur - r - search - 1 < 0 || ur + r + search + 1 >= right_image.cols) {
    return -1.0f;
  }
  // Patches minus their centre value, so that a brightness offset between cameras cancels.
  const int left_centre = left_image.at<std::uint8_t>(v, ul);
  std::vector<int>& costs = *costs_buffer;
  costs.clear();
  for (int offset = -search - 1; offset <= search + 1; ++offset) {
    const int right_centre = right_image.at<std::uint8_t>(v, ur + offset);
    int cost = 0;
    for (int dy = -r; dy <= r; ++dy) {
      const std::uint8_t* left_row = left_image.ptr<std::uint8_t>(v + dy) + ul - r;
      const std::uint8_t* right_row = right_image.ptr<std::uint8_t>(v + dy) + ur + offset - r;
      for (int dx = 0; dx <= 2 * r; ++dx) {
        cost += std::abs((left_row[dx] - left_centre) - (right_row[dx] - right_centre));
      }
    }
    costs.push_back(cost);
  }
  // Best offset strictly inside the window, so that both neighbours exist for the parabola.
  int best = 1;
  for (int k = 1; k < static_cast<int>(costs.size()) - 1; ++k) {
    if (costs[k] < costs[best]) best = k;
  }
  if (costs[best - 1] <= costs[best] || costs[best + 1] <= costs[best]) return -1.0f;
  const double before = costs[best - 1], here = costs[best], after = costs[best + 1];
  const double delta = (before - after) / (2.0 * (before + after - 2.0 * here));
  if (std::abs(delta) > 1.0) return -1.0f;
  // The left patch was centred on the whole pixel ul; the key point may lie a fraction away.
  return static_cast<float>(ur + (best - search - 1) + delta + (left_point.x - ul));
}

}  // namespace stereo_fabmap_slam::features
