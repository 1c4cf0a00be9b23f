#pragma once

#include <cstdint>
#include <ostream>
#include <string>
#include <vector>

#include <opencv2/core.hpp>

#include "stereo_fabmap_slam/concurrency/helper_thread.h"
#include "stereo_fabmap_slam/features/features_options.h"
#include "stereo_fabmap_slam/geometry/stereo_camera.h"
#include "stereo_fabmap_slam/io/option_reader.h"

namespace stereo_fabmap_slam::features {

// Matches left key points to right key points of a rectified pair: candidates lie on the same
// row band and within the disparity range; the best distance (patch or descriptor) must be below
// a limit and clearly better than the second best (ratio test); the right column is then refined
// to a fraction of a pixel by sum-of-absolute-differences correlation along the row and a
// parabola through the best three offsets.
class StereoMatcher {
 public:
  // helper: shares the matching of the left key points (null: the calling thread alone).
  StereoMatcher(const StereoMatcherOptions& options, const geometry::StereoCamera& camera, int norm,
                double max_descriptor_distance, concurrency::HelperThread* helper = nullptr);

  bool uses_descriptors() const { return options_.mode == StereoMatchMode::kDescriptor; }

  // For each left key point, the right column of its match, or -1 (no match, or a depth outside
  // [min_depth, max_depth]). right_descriptors are needed in descriptor mode only.
  std::vector<float> Match(const cv::Mat& left_image, const std::vector<cv::KeyPoint>& left,
                           const cv::Mat& left_descriptors, const cv::Mat& right_image,
                           const std::vector<cv::KeyPoint>& right,
                           const cv::Mat& right_descriptors) const;

 private:
  // A left patch with its sums, computed once per key point.
  struct Patch {
    bool valid = false;
    const cv::Mat* image = nullptr;
    cv::Point centre;
    std::int32_t sum = 0, sum_squares = 0;
  };
  Patch MakePatch(const cv::Mat& image, const cv::Point& centre) const;
  // 1 - zero-mean NCC of a left patch and the right patch around an integer pixel, or 2 if a
  // patch leaves its image or has no texture.
  double PatchDistance(const Patch& left, const cv::Mat& right_image, const cv::Point& right) const;
  // Sub-pixel right column around a key-point match, or a negative value if the correlation has
  // no clear minimum inside the search window. `costs` is scratch space, reused by the caller.
  float RefineColumn(const cv::Mat& left_image, const cv::Point2f& left_point,
                     const cv::Mat& right_image, float right_column, std::vector<int>* costs) const;

  StereoMatcherOptions options_;
  geometry::StereoCamera camera_;
  int norm_;
  double max_descriptor_distance_;
  concurrency::HelperThread* helper_;  // not owned; may be null
};

}  // namespace stereo_fabmap_slam::features
