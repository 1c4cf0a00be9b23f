#pragma once

#include <vector>

#include <opencv2/core.hpp>

namespace stereo_fabmap_slam::features {

// Brute-force matching with Lowe's ratio test: for each row of `query`, its nearest row of
// `train` if that is within max_distance and nearer than `ratio` times the second nearest.
// Used where there is no pose to search by projection (loop verification, relocalization).
std::vector<cv::DMatch> RatioTestMatches(const cv::Mat& query, const cv::Mat& train, int norm,
                                         double max_distance, double ratio);

}  // namespace stereo_fabmap_slam::features
