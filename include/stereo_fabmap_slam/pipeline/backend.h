#pragma once

#include <cstdint>
#include <functional>
#include <map>

#include <Eigen/Geometry>

#include "stereo_fabmap_slam/backend/backend_options.h"
#include "stereo_fabmap_slam/backend/local_bundle_adjuster.h"
#include "stereo_fabmap_slam/geometry/stereo_camera.h"
#include "stereo_fabmap_slam/map/keyframe.h"
#include "stereo_fabmap_slam/map/keyframe_update.h"

namespace stereo_fabmap_slam::pipeline {

struct BackendOutput {
  map::KeyframeUpdate update;  // for the front end's local map and the loop closing
  double bundle_adjustment_ms = 0;
};

// The backend stage: each keyframe joins the windowed bundle adjustment (odom frame), whose
// update goes back to the front end. The Backend nodelet runs the same LocalBundleAdjuster in
// its worker thread.
class Backend {
 public:
  using Clock = std::function<double()>;  // milliseconds, only read to fill the timing

  Backend(const backend::BundleAdjustmentOptions& options, const geometry::StereoCamera& camera,
          Clock clock)
      : bundle_adjuster_(options, camera), clock_(std::move(clock)) {}

  BackendOutput Process(const map::Keyframe& keyframe) {
    BackendOutput output;
    const double start = clock_();
    output.update = bundle_adjuster_.AddKeyframe(keyframe);
    output.bundle_adjustment_ms = clock_() - start;
    return output;
  }

  // Latest pose in odom (T_odom_camera) of every keyframe so far, by id.
  std::map<std::int64_t, Eigen::Isometry3d> KeyframePoses() const {
    return bundle_adjuster_.KeyframePoses();
  }

 private:
  backend::LocalBundleAdjuster bundle_adjuster_;
  Clock clock_;
};

}  // namespace stereo_fabmap_slam::pipeline
