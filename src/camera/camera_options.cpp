#include "stereo_fabmap_slam/camera/camera_options.h"

#include <stdexcept>

namespace stereo_fabmap_slam::camera {

void RectificationOptions::Validate() const {
  if (!(alpha >= 0.0 && alpha <= 1.0)) {
    throw std::invalid_argument("rectification alpha must lie in [0, 1]");
  }
}

}  // namespace stereo_fabmap_slam::camera
