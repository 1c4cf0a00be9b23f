#pragma once

namespace stereo_fabmap_slam::geometry {

// 95 % quantiles of the chi-square distribution: the outlier test of a reprojection error in
// units of the pixel noise, with 2 residuals (mono: u, v) or 3 (stereo: u_left, v, u_right).
constexpr double kChiSquare95TwoDof = 5.991;
constexpr double kChiSquare95ThreeDof = 7.815;

}  // namespace stereo_fabmap_slam::geometry
