#pragma once

#include <ostream>
#include <string>

#include "stereo_fabmap_slam/backend/local_bundle_adjuster.h"
#include "stereo_fabmap_slam/camera/stereo_rectifier.h"
#include "stereo_fabmap_slam/features/feature_options.h"
#include "stereo_fabmap_slam/features/stereo_matcher.h"
#include "stereo_fabmap_slam/odometry/keyframe_policy.h"
#include "stereo_fabmap_slam/odometry/tracker.h"

namespace stereo_fabmap_slam::pipeline {

// Every option of the odometry, one section per module (the sections of config/euroc.yaml).
struct PipelineOptions {
  camera::RectificationOptions rectification;
  features::FeatureOptions features;
  features::StereoMatcherOptions stereo;
  odometry::TrackerOptions tracker;
  odometry::KeyframePolicyOptions keyframes;
  backend::BundleAdjustmentOptions backend;

  // Calls `visit(section name, visitor-accepting options)` for every section.
  template <typename Function>
  void ForEachSection(Function visit);
  void Validate() const;  // throws std::invalid_argument naming the bad value
  void Print(std::ostream& out) const;
};

// Reads a configuration file. A file may start with "include: other.yaml" (relative to itself):
// that file is read first and this one overrides it, so that presets (keyframes_more.yaml) are
// a few lines over config/euroc.yaml. Unknown sections and keys are errors, as are bad values.
PipelineOptions LoadPipelineOptions(const std::string& path);

template <typename Function>
void PipelineOptions::ForEachSection(Function visit) {
  visit("rectification", rectification);
  visit("features", features);
  visit("stereo", stereo);
  visit("tracker", tracker);
  visit("keyframes", keyframes);
  visit("backend", backend);
}

}  // namespace stereo_fabmap_slam::pipeline
