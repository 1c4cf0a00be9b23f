#pragma once

#include <cstddef>
#include <optional>
#include <string>

#include <opencv2/core.hpp>

#include "stereo_fabmap_slam/evaluation/keypoint_transfer.h"

namespace stereo_fabmap_slam::evaluation {

// A plane seen from two views (Oxford affine-covariant sets), or one view twice (identity, for
// illumination changes): x_test ~ H x_reference.
class HomographyTransfer : public KeypointTransfer {
 public:
  // Points carried outside [0, test_size) are out of view.
  HomographyTransfer(const cv::Matx33d& H, const cv::Size& test_size);

  std::optional<cv::Point2f> Transfer(std::size_t index, const cv::Point2f& point) const override;

 private:
  cv::Matx33d H_;
  cv::Size test_size_;
};

// A 3x3 homography from a file: OpenCV FileStorage (.xml, .yml, .yaml, .json; the first matrix
// in it, as opencv-doc's H1to3p.xml) or plain text with nine numbers in row-major order (the
// Oxford H1to2p files). Throws io::InputError naming the file if it cannot be read.
cv::Matx33d ReadHomography(const std::string& path);

}  // namespace stereo_fabmap_slam::evaluation
