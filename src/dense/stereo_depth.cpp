#include "stereo_fabmap_slam/dense/stereo_depth.h"

#include <algorithm>
#include <stdexcept>

#include <opencv2/imgproc.hpp>

#include "stereo_fabmap_slam/dense/disparity_refinement.h"

namespace stereo_fabmap_slam::dense {
namespace {

// Sets the disparity to 0 where the matcher found none (negative) and where the grey levels of
// the left image's size x size window around the pixel vary by less than min_deviation
// (standard deviation; the window reflected at the border, as cv::boxFilter's default). From
// integral images the window's sums are exact integers, so its variance is compared exactly:
// n Q - S^2 < (d n)^2 for n pixels of sum S and sum of squares Q. (Box filters of the float
// image and its square, their products, a square root and mask operations, used before, took
// 2.7-3.5 ms a 752 x 480 pair, and their rounding put a few pixels on the wrong side.)
void ClearUntextured(const cv::Mat& grey, int size, double min_deviation, cv::Mat* disparity) {
  const int radius = size / 2;
  cv::Mat padded;
  cv::copyMakeBorder(grey, padded, radius, radius, radius, radius, cv::BORDER_REFLECT_101);
  cv::Mat sum, squares;  // (rows + 1) x (cols + 1) of the padded image
  cv::integral(padded, sum, squares, CV_32S, CV_64F);
  const double n = static_cast<double>(size) * size;
  const double threshold = min_deviation * min_deviation * n * n;
  const int cols = disparity->cols;
  // The rows on both cores (see DisparityRefinement::Refine).
  cv::parallel_for_(cv::Range(0, disparity->rows), [&](const cv::Range& range) {
    for (int v = range.start; v < range.end; ++v) {
      const int* sum_top = sum.ptr<int>(v);
      const int* sum_bottom = sum.ptr<int>(v + size);
      const double* squares_top = squares.ptr<double>(v);
      const double* squares_bottom = squares.ptr<double>(v + size);
      float* d = disparity->ptr<float>(v);
      for (int u = 0; u < cols; ++u) {  // without a branch: two pixels at a time
        const double s = sum_bottom[u + size] - sum_top[u + size] - sum_bottom[u] + sum_top[u];
        const double q =
            squares_bottom[u + size] - squares_top[u + size] - squares_bottom[u] + squares_top[u];
        d[u] = ((d[u] > 0.0f) & !(n * q - s * s < threshold)) ? d[u] : 0.0f;
      }
    }
  });
}

// Full-resolution disparities (in full-resolution pixels) from the half-resolution matcher's.
// The pyramid's pixel i is centred on full-resolution pixel 2i (cv::pyrDown's 5-tap kernel at
// 2i - 2 ... 2i + 2): pixel 2i takes its own disparity, and an odd pixel 2i + 1, halfway
// between two pyramid pixels (four where row and column are odd), their mean where all of them
// have a match and they agree within a pixel, the most the sub-pixel refinement corrects: a
// surface, on which the mean is where the surface is. Where they differ by more (a depth edge)
// it keeps its left (upper) neighbour's value, as nearest-neighbour resizing did, and the
// refinement decides. Measured against nearest neighbour (docs/benchmarks.md): rendered hall
// mesh median / 90 % [cm] and completeness, loop seed 1 2.17 / 6.88 / 0.769 -> 2.07 / 6.75 /
// 0.773, seed 3 2.32 / 7.59 / 0.755 -> 2.21 / 7.55 / 0.758, figure eight 2.81 / 8.34 / 0.700 ->
// 2.68 / 8.24 / 0.705; MH01's mesh 182,599 -> 182,793 vertices. Leaving the edge pixels
// without depth was a little more accurate on the hall (2.05 / 6.63 on seed 1) but took MH01's
// mesh to 140,688 vertices: real scenes have far more depth edges than the hall. Beyond the
// last pyramid pixel (an odd image size) the last one is repeated.
cv::Mat UpsampleDisparity(const cv::Mat& half, const cv::Size& size) {
  constexpr float kAgreement = 1.0f;  // [px]
  const auto agree = [](float low, float high) { return low > 0.0f && high - low <= kAgreement; };
  cv::Mat full(size, CV_32F);
  const int last_row = half.rows - 1, last_column = half.cols - 1;
  cv::parallel_for_(cv::Range(0, size.height), [&](const cv::Range& range) {
    for (int v = range.start; v < range.end; ++v) {
      // Row v lies on pyramid row v / 2 (even v) or between it and the next (odd v).
      const float* upper = half.ptr<float>(std::min(v / 2, last_row));
      const float* lower = half.ptr<float>(std::min(v / 2 + v % 2, last_row));
      float* out = full.ptr<float>(v);
      for (int j = 0; 2 * j < size.width; ++j) {
        const int own = std::min(j, last_column), next = std::min(j + 1, last_column);
        const float a = upper[own], b = upper[next], c = lower[own], d = lower[next];
        // Column 2j on the pyramid column, 2j + 1 between it and the next: the four values in
        // the same order as for any pixel, so that the sums round alike.
        if (v % 2 == 0) {
          out[2 * j] = a;
          if (2 * j + 1 < size.width) {
            out[2 * j + 1] = agree(std::min(a, b), std::max(a, b)) ? 0.25f * (a + b + a + b) : a;
          }
        } else {
          out[2 * j] = agree(std::min(a, c), std::max(a, c)) ? 0.25f * (a + a + c + c) : a;
          if (2 * j + 1 < size.width) {
            const float low = std::min({a, b, c, d}), high = std::max({a, b, c, d});
            out[2 * j + 1] = agree(low, high) ? 0.25f * (a + b + c + d) : a;
          }
        }
      }
    }
  });
  return full;
}

}  // namespace

StereoDepth::StereoDepth(const StereoDepthOptions& options, const geometry::StereoCamera& camera)
    : options_(options), camera_(camera) {
  options_.Validate();
  if (!(camera_.baseline > 0) || !(camera_.fx > 0)) {
    throw std::invalid_argument(
        "StereoDepth: the camera needs a positive baseline and focal length");
  }
  const int area = options_.block_size * options_.block_size;
  const int scale = options_.matching_scale;
  // At a coarser scale the same depth range needs fewer disparities (SGBM wants a multiple of
  // 16), and the speckle filter's region and range are counted in the matched image's pixels.
  const int disparities = (options_.disparities / scale + 15) / 16 * 16;
  const int speckle_window = options_.speckle_window / (scale * scale);
  const int speckle_range = std::max(1, options_.speckle_range / scale);
  // P1 and P2 as OpenCV's documentation suggests for one channel: the penalties for a change of
  // disparity by one pixel (slanted surfaces) and by more (depth edges) between neighbours.
  // Three-way SGBM: 23 ms a full 752 x 480 pair on the machine of docs/benchmarks.md's first
  // dense figures, against 53 ms for five directions and 80 ms for four-path HH4, which is less
  // biased on the hall's floor seen at a grazing angle (median disparity error -0.17 px with
  // 3-way, 0.00 with HH4; elsewhere 0.03 both) where the sub-pixel refinement removes most of
  // the bias anyway: the budget is 40 ms a keyframe for depth and fusion together.
  matcher_ = cv::StereoSGBM::create(/*minDisparity=*/0, disparities, options_.block_size, 8 * area,
                                    32 * area, options_.left_right_max_difference,
                                    /*preFilterCap=*/63, options_.uniqueness, speckle_window,
                                    speckle_range, cv::StereoSGBM::MODE_SGBM_3WAY);
}

cv::Mat StereoDepth::Disparity(const cv::Mat& left, const cv::Mat& right) const {
  if (left.type() != CV_8UC1 || right.type() != CV_8UC1 || left.size() != right.size() ||
      left.size() != camera_.size) {
    throw std::invalid_argument("StereoDepth: two 8-bit grey images of the camera's size expected");
  }
  const int scale = options_.matching_scale;
  cv::Mat matched_left = left, matched_right = right;
  if (scale == 2) {
    cv::pyrDown(left, matched_left);
    cv::pyrDown(right, matched_right);
  }
  cv::Mat fixed_point;  // CV_16S, 16 x disparity; negative where no match survived
  matcher_->compute(matched_left, matched_right, fixed_point);
  cv::Mat disparity;
  fixed_point.convertTo(disparity, CV_32F, scale / 16.0);
  if (scale != 1) disparity = UpsampleDisparity(disparity, left.size());
  // No disparity where the left window is too flat to match, or the matcher found none.
  ClearUntextured(left, options_.block_size, options_.min_texture, &disparity);
  if (options_.refinement_window != 0) {
    const DisparityRefinement refinement(options_.refinement_window);
    for (int step = 0; step < options_.refinement_steps; ++step) {
      disparity = refinement.Refine(left, right, disparity);
    }
    if (options_.smoothing_window != 0) {
      disparity = SmoothAgreeingDisparities(disparity, options_.smoothing_window,
                                            options_.smoothing_agreement);
    }
  }
  // Last, on the disparities the depth is made of (the smoothing keeps each side of an edge its
  // own values, so the step between them is still there).
  if (options_.edge_jump > 0) {
    ClearDisparityEdges(options_.edge_jump, options_.edge_radius, &disparity);
  }
  return disparity;
}

cv::Mat StereoDepth::DepthFromDisparity(const cv::Mat& disparity) const {
  cv::Mat depth(disparity.size(), CV_32F);
  const float focal_baseline = static_cast<float>(camera_.fx * camera_.baseline);
  const float max_depth = static_cast<float>(options_.max_depth);
  const int rows = disparity.rows, cols = disparity.cols;
  for (int v = 0; v < rows; ++v) {
    const float* d = disparity.ptr<float>(v);
    float* z = depth.ptr<float>(v);
    for (int u = 0; u < cols; ++u) {  // without a branch: four pixels at a time
      const float value = focal_baseline / d[u];
      z[u] = ((d[u] > 0.0f) & (value <= max_depth)) ? value : 0.0f;
    }
  }
  return depth;
}

cv::Mat StereoDepth::Depth(const cv::Mat& left, const cv::Mat& right) const {
  return DepthFromDisparity(Disparity(left, right));
}

}  // namespace stereo_fabmap_slam::dense
