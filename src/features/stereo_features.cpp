#include "stereo_fabmap_slam/features/stereo_features.h"

namespace stereo_fabmap_slam::features {

int StereoFeatures::CountWithDepth() const {
  int count = 0;
  for (std::size_t i = 0; i < size(); ++i) count += HasDepth(i) ? 1 : 0;
  return count;
}

}  // namespace stereo_fabmap_slam::features
