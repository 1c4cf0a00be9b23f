#pragma once

#include <vector>

#include <Eigen/Core>
#include <opencv2/core.hpp>

namespace stereo_fabmap_slam::features {

// Key points of a rectified left image with their descriptors and, where the right image has a
// match, the right column and the triangulated point. Index i refers to one key point everywhere.
struct StereoFeatures {
  std::vector<cv::KeyPoint> keypoints;  // rectified left image
  cv::Mat descriptors;                  // one row per key point
  std::vector<float> u_right;           // column in the rectified right image; < 0: no match
  std::vector<Eigen::Vector3d> points;  // left camera frame [m]; meaningful where HasDepth(i)

  std::size_t size() const { return keypoints.size(); }
  bool HasDepth(std::size_t i) const { return u_right[i] >= 0.0f; }
  int CountWithDepth() const;
};

}  // namespace stereo_fabmap_slam::features
