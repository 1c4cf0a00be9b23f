#include "stereo_fabmap_slam/backend/backend_options.h"

#include <stdexcept>

namespace stereo_fabmap_slam::backend {

void BundleAdjustmentOptions::Visit(io::OptionVisitor& visitor) {
  visitor.Visit("window", &window);
  visitor.Visit("fixed_keyframes", &fixed_keyframes);
  visitor.Visit("iterations", &iterations);
  visitor.Visit("rounds", &rounds);
  visitor.Visit("sigma", &sigma);
  visitor.Visit("threads", &threads);
}

void BundleAdjustmentOptions::Validate() const {
  if (window < 2) throw std::invalid_argument("backend.window must be >= 2");
  if (fixed_keyframes < 1 || fixed_keyframes >= window) {
    throw std::invalid_argument("backend.fixed_keyframes must lie in [1, window)");
  }
  if (iterations < 1 || rounds < 1 || threads < 1) {
    throw std::invalid_argument("backend iterations, rounds and threads must be >= 1");
  }
  if (!(sigma > 0)) throw std::invalid_argument("backend.sigma must be > 0");
}

}  // namespace stereo_fabmap_slam::backend
