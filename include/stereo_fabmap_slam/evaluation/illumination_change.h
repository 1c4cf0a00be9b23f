#pragma once

#include <string>
#include <vector>

#include <opencv2/core.hpp>

namespace stereo_fabmap_slam::evaluation {

// A rendered change of lighting on a fixed view, so that every key point's true position is
// where it was: out = 255 * (gain * shading * in / 255) ^ gamma, saturated to 8 bits, where the
// shading of a directional light ramps linearly from light_min on one side of the image to 1 on
// the other, along light_angle_deg (0: dark on the left, bright on the right; 90: dark on top).
struct IlluminationChange {
  std::string name;
  double gain = 1.0;
  double gamma = 1.0;
  double light_min = 1.0;  // 1: no directional light
  double light_angle_deg = 0.0;

  void Validate() const;  // throws std::invalid_argument naming the bad value
};

// 8-bit grey in, 8-bit grey of the same size out. Throws std::invalid_argument otherwise.
cv::Mat ApplyIlluminationChange(const cv::Mat& image, const IlluminationChange& change);

// Exposure (darker and brighter with clipping), gamma both ways, and two directional lights.
std::vector<IlluminationChange> StandardIlluminationChanges();

}  // namespace stereo_fabmap_slam::evaluation
