#pragma once

#include <opencv2/core.hpp>

namespace stereo_fabmap_slam::dense {

// Sub-pixel refinement of a disparity image by one step of one-dimensional Lucas-Kanade: the
// right image is warped onto the left one with every pixel's own disparity, and in a window
// around each pixel the disparity step and a grey-level offset that best explain the remaining
// difference are solved for by least squares (the offset absorbs the two cameras' different
// exposure). Semi-global matching fits a parabola through three integer costs of a small window,
// which leaves a bias toward whole pixels and the noise of few pixels; the warped difference has
// no such bias, and a larger window averages the noise (three pairs of the rendered hall: median
// disparity error 0.139 / 0.177 / 0.159 -> 0.088 / 0.156 / 0.113 px, the floor's bias -0.044 ->
// -0.010 px; docs/benchmarks.md). One step: a second one, from the refined disparities, made
// the fused mesh no better on the rendered loop (median 2.27 -> 2.35 cm). Only pixels with a
// disparity (> 0) are refined and take part in their neighbours' windows; a pixel whose step leaves
// the matched pixel, or whose window has no gradient to solve with, loses its disparity.
class DisparityRefinement {
 public:
  // window: odd, >= 3 [px]. Throws std::invalid_argument otherwise.
  explicit DisparityRefinement(int window);

  // left, right: rectified 8-bit grey; disparity: CV_32F of their size, 0 where none.
  cv::Mat Refine(const cv::Mat& left, const cv::Mat& right, const cv::Mat& disparity) const;

 private:
  int window_;
};

// The mean of a disparity image's values (> 0) over a window x window neighbourhood of each
// pixel with a disparity, where it lies within `agreement` [px] of the pixel's own value (else
// the pixel keeps its own). See StereoDepthOptions::smoothing_window for why. window: odd, >= 3;
// disparity: CV_32F. Throws std::invalid_argument otherwise.
cv::Mat SmoothAgreeingDisparities(const cv::Mat& disparity, int window, double agreement);

// Clears (sets to 0) the disparity of every pixel within `radius` [px] (a square) of a depth
// edge: a pixel with a disparity (> 0) that differs from one of its 8 neighbours' by more than
// `jump` [px] (neighbours without a disparity do not count). See
// StereoDepthOptions::edge_jump for why. disparity: CV_32F; jump > 0, radius >= 0. Throws
// std::invalid_argument otherwise.
void ClearDisparityEdges(double jump, int radius, cv::Mat* disparity);

}  // namespace stereo_fabmap_slam::dense
