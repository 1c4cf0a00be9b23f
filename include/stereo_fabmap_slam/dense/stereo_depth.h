#pragma once

#include <opencv2/calib3d.hpp>
#include <opencv2/core.hpp>

#include "stereo_fabmap_slam/dense/dense_options.h"
#include "stereo_fabmap_slam/geometry/stereo_camera.h"

namespace stereo_fabmap_slam::dense {

// Depth of every reliable pixel of a rectified left image (semi-global matching with a
// left-right check, uniqueness, speckle and texture filtering, a distance limit). Not
// thread-safe (one matcher's buffers); one object per thread.
class StereoDepth {
 public:
  // Throws std::invalid_argument for invalid options or a camera without a baseline.
  StereoDepth(const StereoDepthOptions& options, const geometry::StereoCamera& camera);

  // Disparity [px] of the left image's pixels (CV_32F), 0 where no reliable match was found.
  // Both images rectified, 8-bit grey, of the camera's size.
  cv::Mat Disparity(const cv::Mat& left, const cv::Mat& right) const;
  // Depth [m] along the left camera's optical axis (CV_32F), 0 where unreliable or beyond
  // max_depth.
  cv::Mat Depth(const cv::Mat& left, const cv::Mat& right) const;
  // Depth from a disparity image made by Disparity().
  cv::Mat DepthFromDisparity(const cv::Mat& disparity) const;

  const StereoDepthOptions& options() const { return options_; }

 private:
  StereoDepthOptions options_;
  geometry::StereoCamera camera_;
  cv::Ptr<cv::StereoSGBM> matcher_;
};

}  // namespace stereo_fabmap_slam::dense
