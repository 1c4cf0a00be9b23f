#include "stereo_fabmap_slam/evaluation/illumination_change.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <stdexcept>

namespace stereo_fabmap_slam::evaluation {

void IlluminationChange::Validate() const {
  if (!(gain > 0)) throw std::invalid_argument("illumination " + name + ": gain must be > 0");
  if (!(gamma > 0)) throw std::invalid_argument("illumination " + name + ": gamma must be > 0");
  if (!(light_min > 0 && light_min <= 1)) {
    throw std::invalid_argument("illumination " + name + ": light_min must be in (0, 1]");
  }
}

cv::Mat ApplyIlluminationChange(const cv::Mat& image, const IlluminationChange& change) {
  change.Validate();
  if (image.empty() || image.type() != CV_8UC1) {
    throw std::invalid_argument("illumination changes need a non-empty 8-bit grey image");
  }
  // The light's direction as a unit vector; each pixel's position along it, from 0 on the dark
  // side to 1 on the bright side, sets its shading.
  const double angle = change.light_angle_deg * M_PI / 180.0;
  const double dx = std::cos(angle), dy = std::sin(angle);
  const double w = image.cols - 1, h = image.rows - 1;
  const double low = std::min(0.0, dx * w) + std::min(0.0, dy * h);
  const double high = std::max(0.0, dx * w) + std::max(0.0, dy * h);
  const double span = high > low ? high - low : 1.0;
  cv::Mat out(image.size(), CV_8UC1);
  for (int y = 0; y < image.rows; ++y) {
    const std::uint8_t* in_row = image.ptr<std::uint8_t>(y);
    std::uint8_t* out_row = out.ptr<std::uint8_t>(y);
    for (int x = 0; x < image.cols; ++x) {
      const double along = (dx * x + dy * y - low) / span;
      const double shading = change.light_min + (1.0 - change.light_min) * along;
      const double linear = std::min(1.0, change.gain * shading * in_row[x] / 255.0);
      out_row[x] = cv::saturate_cast<std::uint8_t>(255.0 * std::pow(linear, change.gamma));
    }
  }
  return out;
}

std::vector<IlluminationChange> StandardIlluminationChanges() {
  // Exposure as a camera's auto-exposure makes it (half and 1.6 times the light, the latter
  // clipping highlights), a non-linear response both ways, and a lamp to one side: the shading
  // ramps from a quarter of the light to full across the image.
  std::vector<IlluminationChange> changes(6);
  changes[0].name = "gain0.5";
  changes[0].gain = 0.5;
  changes[1].name = "gain1.6";
  changes[1].gain = 1.6;
  changes[2].name = "gamma0.6";
  changes[2].gamma = 0.6;
  changes[3].name = "gamma1.8";
  changes[3].gamma = 1.8;
  changes[4].name = "light_from_right";
  changes[4].light_min = 0.25;
  changes[4].light_angle_deg = 0;
  changes[5].name = "light_from_top_left";
  changes[5].light_min = 0.25;
  changes[5].light_angle_deg = 225;
  return changes;
}

}  // namespace stereo_fabmap_slam::evaluation
