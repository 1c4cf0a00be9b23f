#include "stereo_fabmap_slam/dense/disparity_refinement.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <stdexcept>
#include <vector>

#include <opencv2/imgproc.hpp>

namespace stereo_fabmap_slam::dense {
namespace {

// Bands of rows for cv::parallel_for_, four a thread, where each task's setup (a buffer, its
// scheduling) costs: OpenCV's default is a task a row.
double RowBands() { return 4.0 * cv::getNumThreads(); }

// The sum over a window x window neighbourhood of every pixel (nothing outside the image).
cv::Mat WindowSum(const cv::Mat& image, int window) {
  cv::Mat sum;
  cv::boxFilter(image, sum, CV_32F, cv::Size(window, window), cv::Point(-1, -1),
                /*normalize=*/false, cv::BORDER_CONSTANT);
  return sum;
}

}  // namespace

DisparityRefinement::DisparityRefinement(int window) : window_(window) {
  if (window_ < 3 || window_ % 2 == 0) {
    throw std::invalid_argument("DisparityRefinement: the window must be odd and at least 3 px");
  }
}

cv::Mat DisparityRefinement::Refine(const cv::Mat& left, const cv::Mat& right,
                                    const cv::Mat& disparity) const {
  if (left.type() != CV_8UC1 || right.type() != CV_8UC1 || disparity.type() != CV_32FC1 ||
      left.size() != right.size() || left.size() != disparity.size()) {
    throw std::invalid_argument(
        "DisparityRefinement: two 8-bit grey images and a float disparity of their size expected");
  }
  // Per pixel with a disparity, the right image at x - d(x) on its row and the row derivative
  // there (central difference of the right image, warped as the image is: the difference of the
  // warped image instead is wrong wherever the disparity changes from pixel to pixel, mesh
  // median 2.27 -> 2.57 cm on the rendered loop), both linearly interpolated with the borders
  // replicated; then the residual e = R(x - d) - L(x) and the gradient g, their products, and
  // the pixel's count, 0 where there is no disparity. One pass instead of cv::remap and image
  // arithmetic: the rows are all it needs (rectified pairs), and remap's bilinear weights are
  // quantised to 1/32 px, which the sub-pixel step inherits.
  const int rows = disparity.rows, cols = disparity.cols;
  cv::Mat terms(disparity.size(), CV_32FC4);  // g, e, g g, g e
  cv::Mat mask(disparity.size(), CV_8U);      // 1 where there is a disparity: summed in integers
  // The rows on both cores (each row on its own: the same values on any number of threads). In
  // the ROS graph the dense map's worker and its threads run at idle priority, so this takes
  // only time that tracking leaves: depth 16.6-17.6 -> 15.3-15.6 ms on MH01 offline, unchanged
  // in the graph, where the second core is rarely idle while a keyframe is fused. In bands of
  // rows (RowBands), so that the gradient's buffer is allocated once a band, not once a row.
  cv::parallel_for_(
      cv::Range(0, rows),
      [&](const cv::Range& range) {
        std::vector<float> gradient_row(static_cast<std::size_t>(cols));
        for (int v = range.start; v < range.end; ++v) {
          const std::uint8_t* r = right.ptr<std::uint8_t>(v);
          const std::uint8_t* l = left.ptr<std::uint8_t>(v);
          const float* d = disparity.ptr<float>(v);
          for (int i = 0; i < cols; ++i) {
            const int before = std::max(i - 1, 0), after = std::min(i + 1, cols - 1);
            gradient_row[static_cast<std::size_t>(i)] =
                0.5f * (static_cast<float>(r[after]) - r[before]);
          }
          cv::Vec4f* out = terms.ptr<cv::Vec4f>(v);
          std::uint8_t* m = mask.ptr<std::uint8_t>(v);
          for (int u = 0; u < cols; ++u) {
            // A disparity no pair of pixels can have (not finite, or the image's width or more) is
            // treated as none: the cast below is defined only in range.
            if (!(d[u] > 0.0f && d[u] < cols)) {
              out[u] = cv::Vec4f(0.0f, 0.0f, 0.0f, 0.0f);
              m[u] = 0;
              continue;
            }
            const float x = static_cast<float>(u) - d[u];
            const float floor_x = std::floor(x);
            const float a = x - floor_x;
            const int x0 = std::clamp(static_cast<int>(floor_x), 0, cols - 1);
            const int x1 = std::clamp(static_cast<int>(floor_x) + 1, 0, cols - 1);
            const float warped = (1.0f - a) * r[x0] + a * r[x1];
            const float g = (1.0f - a) * gradient_row[static_cast<std::size_t>(x0)] +
                            a * gradient_row[static_cast<std::size_t>(x1)];
            const float e = warped - static_cast<float>(l[u]);
            out[u] = cv::Vec4f(g, e, g * g, g * e);
            m[u] = 1;
          }
        }
      },
      RowBands());
  cv::Mat sums;
  cv::boxFilter(terms, sums, CV_32F, cv::Size(window_, window_), cv::Point(-1, -1),
                /*normalize=*/false, cv::BORDER_CONSTANT);
  const cv::Mat count = WindowSum(mask, window_);

  // R(x - d - step) ~ R(x - d) - g step: least squares of e - g step - offset over the window
  // gives step = cov(g, e) / var(g) (sums over the window's pixels with a disparity).
  // Without a branch, every pixel's step computed and kept or not (0: no disparity), so that
  // GCC computes four pixels at a time; the same values as testing each pixel in turn.
  cv::Mat refined(disparity.size(), CV_32F);
  const float width = static_cast<float>(cols);
  cv::parallel_for_(cv::Range(0, rows), [&](const cv::Range& range) {
    for (int v = range.start; v < range.end; ++v) {
      const float* d = disparity.ptr<float>(v);
      const float* n = count.ptr<float>(v);
      const cv::Vec4f* sum = sums.ptr<cv::Vec4f>(v);  // g, e, g g, g e
      float* out = refined.ptr<float>(v);
      for (int u = 0; u < cols; ++u) {
        const bool has_disparity = (d[u] > 0.0f) & (d[u] < width);
        const float sg = sum[u][0], se = sum[u][1], sgg = sum[u][2], sge = sum[u][3];
        const float variance = sgg - sg * sg / n[u];
        const float step = (sge - sg * se / n[u]) / variance;
        const float refined_disparity = d[u] + step;
        // No gradient across the window: the step is undetermined. 1e-3 grey levels squared per
        // pixel is far below any texture the matcher keeps (its min_texture: 4 levels). And the
        // matcher found the right pixel; a step out of it is a failed refinement (an occlusion
        // edge in the window, repeated texture), not a better match.
        const bool refined_here = has_disparity & (variance > 1e-3f * n[u]) &
                                  (std::abs(step) <= 1.0f) & (refined_disparity > 0.0f);
        out[u] = refined_here ? refined_disparity : 0.0f;
      }
    }
  });
  return refined;
}

cv::Mat SmoothAgreeingDisparities(const cv::Mat& disparity, int window, double agreement) {
  if (window < 3 || window % 2 == 0 || disparity.type() != CV_32FC1) {
    throw std::invalid_argument(
        "SmoothAgreeingDisparities: a float disparity and an odd window of at least 3 px expected");
  }
  // One pass: the values (0 where there is none: a NaN would spread over the window) and an
  // 8-bit mask of where there is one, whose window sums OpenCV takes in integers (a float
  // image's in doubles), the same counts.
  cv::Mat values(disparity.size(), CV_32F);
  cv::Mat with_disparity(disparity.size(), CV_8U);
  const int cols = disparity.cols;  // a local: the mask's bytes could alias the Mat's members
  cv::parallel_for_(cv::Range(0, disparity.rows), [&](const cv::Range& range) {
    for (int v = range.start; v < range.end; ++v) {
      const float* d = disparity.ptr<float>(v);
      float* out = values.ptr<float>(v);
      std::uint8_t* mask = with_disparity.ptr<std::uint8_t>(v);
      for (int u = 0; u < cols; ++u) {
        const bool has = d[u] > 0.0f;
        out[u] = has ? d[u] : 0.0f;
        mask[u] = has ? 1 : 0;
      }
    }
  });
  const cv::Mat sum = WindowSum(values, window), count = WindowSum(with_disparity, window);
  cv::Mat& smoothed = values;  // its sums are taken: the values may change in place
  const float limit = static_cast<float>(agreement);
  cv::parallel_for_(cv::Range(0, smoothed.rows), [&](const cv::Range& range) {
    for (int v = range.start; v < range.end; ++v) {
      float* d = smoothed.ptr<float>(v);
      const float* s = sum.ptr<float>(v);
      const float* n = count.ptr<float>(v);
      for (int u = 0; u < cols; ++u) {
        const float mean = s[u] / n[u];  // where there is no disparity, 0 / n or 0 / 0: not used
        d[u] = ((d[u] > 0.0f) & (std::abs(mean - d[u]) <= limit)) ? mean : d[u];
      }
    }
  });
  return smoothed;
}

void ClearDisparityEdges(double jump, int radius, cv::Mat* disparity) {
  if (disparity == nullptr || disparity->type() != CV_32FC1 || !(jump > 0) || radius < 0) {
    throw std::invalid_argument(
        "ClearDisparityEdges: a float disparity, a jump > 0 and a radius >= 0 expected");
  }
  // Each pixel against its 8 neighbours, without a branch inside the rows; at the image's border
  // a missing neighbour is replaced by the pixel itself (no step). The rows on both cores, in
  // bands (RowBands). (OpenCV's dilation and erosion for the
  // neighbourhood's largest and smallest disparity, used first, with the masks they need, made
  // this function 2.5 ms a 752 x 480 pair on the slower machine; now 0.9 ms.)
  cv::Mat edge(disparity->size(), CV_8U);
  const float limit = static_cast<float>(jump);
  // Locals: the mask's bytes could alias the Mat's members.
  const int rows = disparity->rows, cols = disparity->cols;
  const auto apart = [limit](float neighbour, float own) {
    return (neighbour > 0.0f) & (std::abs(neighbour - own) > limit);
  };
  cv::parallel_for_(
      cv::Range(0, rows),
      [&](const cv::Range& range) {
        for (int v = range.start; v < range.end; ++v) {
          const float* row = disparity->ptr<float>(v);
          const float* above = disparity->ptr<float>(v > 0 ? v - 1 : v);
          const float* below = disparity->ptr<float>(v + 1 < rows ? v + 1 : v);
          std::uint8_t* e = edge.ptr<std::uint8_t>(v);
          // Pixel u against the neighbours in columns `left`, u and `right` of the three rows.
          const auto edge_at = [&](int left, int u, int right) -> std::uint8_t {
            const float own = row[u];
            std::uint8_t step = 0;
            step |= apart(above[left], own);
            step |= apart(above[u], own);
            step |= apart(above[right], own);
            step |= apart(row[left], own);
            step |= apart(row[right], own);
            step |= apart(below[left], own);
            step |= apart(below[u], own);
            step |= apart(below[right], own);
            return own > 0.0f ? static_cast<std::uint8_t>(step * 255) : 0;
          };
          e[0] = edge_at(0, 0, std::min(1, cols - 1));
          e[cols - 1] = edge_at(std::max(cols - 2, 0), cols - 1, cols - 1);
          for (int u = 1; u + 1 < cols; ++u) e[u] = edge_at(u - 1, u, u + 1);
        }
      },
      RowBands());
  if (radius > 0) {
    cv::dilate(edge, edge,
               cv::getStructuringElement(cv::MORPH_RECT, cv::Size(2 * radius + 1, 2 * radius + 1)));
  }
  disparity->setTo(0.0f, edge);
}

}  // namespace stereo_fabmap_slam::dense
