#pragma once

#include "stereo_fabmap_slam/io/option_reader.h"

namespace stereo_fabmap_slam::camera {

struct RectificationOptions {
  static constexpr char kSection[] = "rectification";

  // OpenCV's free scaling: 0 keeps only valid pixels (no black borders that would make edges
  // for the detector), 1 keeps every raw pixel.
  double alpha = 0.0;
  void Visit(io::OptionVisitor& visitor) { visitor.Visit("alpha", &alpha); }
  void Validate() const;
};

}  // namespace stereo_fabmap_slam::camera
