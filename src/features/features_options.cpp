#include "stereo_fabmap_slam/features/features_options.h"

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

void StereoMatcherOptions::Visit(io::OptionVisitor& visitor) {
  static constexpr io::EnumName<StereoMatchMode> kModes[] = {
      {StereoMatchMode::kPatch, "patch"}, {StereoMatchMode::kDescriptor, "descriptor"}};
  io::VisitEnum(visitor, "mode", &mode, kModes);
  visitor.Visit("max_patch_distance", &max_patch_distance);
  visitor.Visit("max_row_difference", &max_row_difference);
  visitor.Visit("max_disparity", &max_disparity);
  visitor.Visit("ratio", &ratio);
  visitor.Visit("min_depth", &min_depth);
  visitor.Visit("max_depth", &max_depth);
  visitor.Visit("subpixel", &subpixel);
  visitor.Visit("patch_radius", &patch_radius);
  visitor.Visit("search_radius", &search_radius);
}

void StereoMatcherOptions::Validate() const {
  if (!(max_patch_distance > 0 && max_patch_distance <= 2)) {
    throw std::invalid_argument("stereo.max_patch_distance must lie in (0, 2]");
  }
  if (!(max_row_difference >= 0))
    throw std::invalid_argument("stereo.max_row_difference must be >= 0");
  if (!(max_disparity > 0)) throw std::invalid_argument("stereo.max_disparity must be > 0");
  if (!(ratio > 0 && ratio <= 1)) throw std::invalid_argument("stereo.ratio must lie in (0, 1]");
  if (!(min_depth > 0 && max_depth > min_depth)) {
    throw std::invalid_argument("stereo depths need 0 < min_depth < max_depth");
  }
  if (patch_radius < 1 || search_radius < 1) {
    throw std::invalid_argument("stereo.patch_radius and search_radius must be >= 1");
  }
}

}  // namespace stereo_fabmap_slam::features
