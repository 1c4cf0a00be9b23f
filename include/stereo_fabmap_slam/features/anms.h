#pragma once

#include <vector>

#include <opencv2/core.hpp>

namespace stereo_fabmap_slam::features {

// Adaptive non-maximal suppression by square covering (SSC; Bailo et al., Pattern Recognition
// Letters 2018): keeps about `count` key points, strongest first, each suppressing the others in
// a square around it whose size is found by binary search, so that the kept points spread over
// the image instead of piling up on the most textured part. Returns all points if there are no
// more than `count`. `tolerance`: the result may have count * (1 +- tolerance) points.
std::vector<cv::KeyPoint> SelectWithAnms(std::vector<cv::KeyPoint> keypoints, int count,
                                         const cv::Size& image_size, double tolerance);

// The `count` strongest key points (all if fewer), strongest first.
std::vector<cv::KeyPoint> SelectStrongest(std::vector<cv::KeyPoint> keypoints, int count);

}  // namespace stereo_fabmap_slam::features
