#pragma once

#include <cstdint>

namespace stereo_fabmap_slam::backend {

// A map point seen in a keyframe: the left image's key point and the right image's column of
// its stereo match (u_right < 0: mono), rectified pixels.
struct PointObservation {
  std::int64_t keyframe;
  float u, v, u_right;
};

}  // namespace stereo_fabmap_slam::backend
