#pragma once

#include <functional>

#include <opencv2/core.hpp>

#include "stereo_fabmap_slam/camera/stereo_rectifier.h"
#include "stereo_fabmap_slam/features/features_options.h"
#include "stereo_fabmap_slam/features/stereo_feature_extractor.h"
#include "stereo_fabmap_slam/odometry/odometry_options.h"
#include "stereo_fabmap_slam/odometry/tracker.h"

namespace stereo_fabmap_slam::pipeline {

// The options of the modules the front end is built from, each read from its own section.
struct FrontEndOptions {
  features::FeatureOptions features;
  features::StereoMatcherOptions stereo;
  odometry::TrackerOptions tracker;
  odometry::KeyframePolicyOptions keyframes;

  // Calls visit(options) for each module's options, e.g. to read, validate or print them all.
  template <typename Visit>
  void ForEachModule(Visit visit) {
    visit(features);
    visit(stereo);
    visit(tracker);
    visit(keyframes);
  }
};

// Milliseconds spent per stage of one frame.
struct FrameTiming {
  double rectification_ms = 0, detection_ms = 0, description_ms = 0, stereo_ms = 0, tracking_ms = 0,
         bundle_adjustment_ms = 0;
  // Detection to refined pose: what a frame costs before the next one can be tracked.
  double TrackingTotal() const { return detection_ms + description_ms + stereo_ms + tracking_ms; }
};

struct FrontEndOutput {
  odometry::TrackingResult tracking;
  FrameTiming timing;
};

// Rectify, extract stereo features, track: everything of a frame up to its pose and keyframe
// decision. The offline pipeline adds the bundle adjustment in the same thread; the
// StereoTracker nodelet sends the keyframes to the Backend nodelet instead. The clock
// (milliseconds) is only read to fill FrameTiming.
class StereoFrontEnd {
 public:
  using Clock = std::function<double()>;

  StereoFrontEnd(const FrontEndOptions& options, camera::StereoRectifier rectifier, Clock clock);

  // Raw (unrectified) mono8 images of the calibrated size; throws std::invalid_argument otherwise.
  FrontEndOutput Process(double timestamp, const cv::Mat& left_raw, const cv::Mat& right_raw);
  void ApplyUpdate(const map::KeyframeUpdate& update) { tracker_.ApplyUpdate(update); }
  void Reset() { tracker_.Reset(); }

  const geometry::StereoCamera& camera() const { return rectifier_.camera(); }

 private:
  camera::StereoRectifier rectifier_;
  Clock clock_;
  features::StereoFeatureExtractor extractor_;
  odometry::Tracker tracker_;
};

}  // namespace stereo_fabmap_slam::pipeline
