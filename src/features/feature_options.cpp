#include "stereo_fabmap_slam/features/feature_options.h"

#include <stdexcept>
#include <string>

namespace stereo_fabmap_slam::features {

void FeatureOptions::Visit(io::OptionVisitor& visitor) {
  visitor.Visit("detector", &detector);
  visitor.Visit("descriptor", &descriptor);
  visitor.Visit("max_features", &max_features);
  visitor.Visit("max_right_features", &max_right_features);
  visitor.Visit("detector_threshold", &detector_threshold);
  visitor.Visit("adaptive_threshold", &adaptive_threshold);
  visitor.Visit("min_detector_threshold", &min_detector_threshold);
  visitor.Visit("max_detector_threshold", &max_detector_threshold);
  visitor.Visit("parallel", &parallel);
  visitor.Visit("anms", &anms);
  visitor.Visit("anms_tolerance", &anms_tolerance);
}

void FeatureOptions::Validate() const {
  if (max_features < 10) throw std::invalid_argument("features.max_features must be at least 10");
  if (max_right_features < max_features) {
    throw std::invalid_argument("features.max_right_features must be at least max_features");
  }
  if (min_detector_threshold < 1 || max_detector_threshold > 255 ||
      detector_threshold < min_detector_threshold || detector_threshold > max_detector_threshold) {
    throw std::invalid_argument(
        "features: need 1 <= min_detector_threshold <= detector_threshold <= "
        "max_detector_threshold <= 255");
  }
  if (!(anms_tolerance > 0 && anms_tolerance < 1)) {
    throw std::invalid_argument("features.anms_tolerance must lie in (0, 1)");
  }
}

}  // namespace stereo_fabmap_slam::features
