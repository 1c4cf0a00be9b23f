#pragma once

#include <vector>

#include <Eigen/Core>
#include <opencv2/core.hpp>

namespace stereo_fabmap_slam::geometry {

// How many cells of a grid x grid partition of the image hold at least one of the pixels: the
// spread of a set of inliers. A pose verified by inliers on one small object (a poster repeated
// elsewhere) covers few cells; a view of a place covers many.
int OccupiedCells(const std::vector<Eigen::Vector2d>& pixels, const cv::Size& size, int grid);
// The grid the loop detector, relocalization and the tracker's far jumps count inlier cells on
// (their min_inlier_cells options are cells of it).
inline constexpr int kInlierSpreadGrid = 4;

}  // namespace stereo_fabmap_slam::geometry
