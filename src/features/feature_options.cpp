#include "stereo_fabmap_slam/features/feature_options.h"

#include <stdexcept>
#include <string>

namespace stereo_fabmap_slam::features {

void FeatureOptions::Load(io::OptionReader& reader) {
  reader.Read("detector", &detector);
  reader.Read("descriptor", &descriptor);
  reader.Read("max_features", &max_features);
  reader.Read("max_right_features", &max_right_features);
  reader.Read("detector_threshold", &detector_threshold);
  reader.Read("adaptive_threshold", &adaptive_threshold);
  reader.Read("min_detector_threshold", &min_detector_threshold);
  reader.Read("max_detector_threshold", &max_detector_threshold);
  reader.Read("parallel", &parallel);
  reader.Read("anms", &anms);
  reader.Read("anms_tolerance", &anms_tolerance);
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

std::ostream& operator<<(std::ostream& out, const FeatureOptions& o) {
  return out << "features: detector " << o.detector << ", descriptor " << o.descriptor
             << ", max_features " << o.max_features << ", max_right_features "
             << o.max_right_features << ", detector_threshold " << o.detector_threshold
             << (o.adaptive_threshold
                     ? " adaptive in [" + std::to_string(o.min_detector_threshold) + ", " +
                           std::to_string(o.max_detector_threshold) + "]"
                     : std::string(" fixed"))
             << ", parallel " << (o.parallel ? "on" : "off") << ", anms " << (o.anms ? "on" : "off")
             << " (tolerance " << o.anms_tolerance << ")";
}

}  // namespace stereo_fabmap_slam::features
