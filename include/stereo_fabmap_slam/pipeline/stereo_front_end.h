#pragma once

#include <functional>
#include <memory>
#include <optional>

#include <opencv2/core.hpp>

#include "stereo_fabmap_slam/camera/stereo_rectifier.h"
#include "stereo_fabmap_slam/concurrency/helper_thread.h"
#include "stereo_fabmap_slam/features/features_options.h"
#include "stereo_fabmap_slam/features/stereo_feature_extractor.h"
#include "stereo_fabmap_slam/odometry/odometry_options.h"
#include "stereo_fabmap_slam/odometry/tracker.h"
#include "stereo_fabmap_slam/place_recognition/image_describer.h"

namespace stereo_fabmap_slam::pipeline {

// The options of the modules the front end is built from, each read from its own section.
struct FrontEndOptions {
  features::FeatureOptions features;
  features::StereoMatcherOptions stereo;
  odometry::TrackerOptions tracker;
  odometry::KeyframePolicyOptions keyframes;
  // Place recognition's detector selection (config/fabmap.yaml): when set, every keyframe
  // carries place descriptors of its rectified left image, computed once here.
  std::optional<features::FeatureOptions> place_features;

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
         place_description_ms = 0, bundle_adjustment_ms = 0, loop_detection_ms = 0,
         pose_graph_ms = 0, relocalization_ms = 0;
  // Detection to refined pose: what a frame costs before the next one can be tracked.
  double TrackingTotal() const { return detection_ms + description_ms + stereo_ms + tracking_ms; }
};

struct FrontEndOutput {
  odometry::TrackingResult tracking;
  FrameTiming timing;
  // The frame's stereo features (a copy of what the tracker used), for relocalization; empty
  // without place features.
  features::StereoFeatures features;
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
  // `frames_skipped`: stereo pairs passed over since the last one processed (Tracker::Track).
  FrontEndOutput Process(double timestamp, const cv::Mat& left_raw, const cv::Mat& right_raw,
                         int frames_skipped = 0);
  // Place descriptors of the last processed frame's rectified left image (empty without place
  // features): computed on demand, as only keyframes and relocalization attempts need them.
  cv::Mat DescribeLastFrame() const;
  // The stereo features of a stereo pair, without tracking it (e.g. to check a view against the
  // map); `place_descriptors` receives its place descriptors (empty without place features).
  features::StereoFeatures Extract(const cv::Mat& left_raw, const cv::Mat& right_raw,
                                   cv::Mat* place_descriptors) const;
  void ApplyUpdate(const map::KeyframeUpdate& update) { tracker_.ApplyUpdate(update); }
  void Reset() { tracker_.Reset(); }
  void SetStartPose(const Eigen::Isometry3d& T_odom_camera) {
    tracker_.SetStartPose(T_odom_camera);
  }
  void StartNewLocalMap() { tracker_.StartNewLocalMap(); }
  void SkipIdsBelow(std::int64_t keyframe_id, std::int64_t point_id) {
    tracker_.SkipIdsBelow(keyframe_id, point_id);
  }

  const geometry::StereoCamera& camera() const { return rectifier_.camera(); }
  // The last processed frame's rectified left image (shared, not copied).
  const cv::Mat& last_rectified_left() const { return last_left_; }
  int descriptor_norm() const { return extractor_.descriptor_norm(); }
  double max_match_distance() const { return extractor_.max_match_distance(); }

 private:
  camera::StereoRectifier rectifier_;
  Clock clock_;
  // The second thread of every stage that splits its work (docs/benchmarks.md, "A front end
  // under 5 ms"); null when neither features.parallel nor tracker.parallel.
  std::unique_ptr<concurrency::HelperThread> helper_;
  concurrency::HelperThread* rectification_helper_;  // helper_ if features.parallel
  features::StereoFeatureExtractor extractor_;
  odometry::Tracker tracker_;
  std::unique_ptr<place_recognition::ImageDescriber> place_describer_;  // null: no places
  cv::Mat last_left_;                                                   // rectified
};

}  // namespace stereo_fabmap_slam::pipeline
