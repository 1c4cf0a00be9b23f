#pragma once

#include <cstddef>
#include <optional>

#include <opencv2/core.hpp>

namespace stereo_fabmap_slam::evaluation {

// The known geometry between a reference and a test image, as descriptor precision-recall needs
// it: where a reference key point appears in the test image. A key point the geometry cannot
// carry (it leaves the test view, or it has no depth) takes no part in the measure, because
// whether its match is right cannot be known.
class KeypointTransfer {
 public:
  virtual ~KeypointTransfer() = default;

  // Position in the test image of reference key point `index` (at `point` in the reference
  // image), or nothing.
  virtual std::optional<cv::Point2f> Transfer(std::size_t index,
                                              const cv::Point2f& point) const = 0;
};

}  // namespace stereo_fabmap_slam::evaluation
