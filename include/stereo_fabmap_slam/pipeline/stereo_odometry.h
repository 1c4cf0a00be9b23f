#pragma once

#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include <opencv2/core.hpp>

#include "stereo_fabmap_slam/backend/local_bundle_adjuster.h"
#include "stereo_fabmap_slam/camera/stereo_rectifier.h"
#include "stereo_fabmap_slam/evaluation/trajectory.h"
#include "stereo_fabmap_slam/features/stereo_feature_extractor.h"
#include "stereo_fabmap_slam/odometry/tracker.h"
#include "stereo_fabmap_slam/pipeline/pipeline_options.h"

namespace stereo_fabmap_slam::pipeline {

// Milliseconds spent per stage of one frame.
struct FrameTiming {
  double rectification_ms = 0, detection_ms = 0, description_ms = 0, stereo_ms = 0, tracking_ms = 0,
         bundle_adjustment_ms = 0;
  // Detection to refined pose: what a frame costs before the next one can be tracked.
  double TrackingTotal() const { return detection_ms + description_ms + stereo_ms + tracking_ms; }
};

struct FrameRecord {
  double timestamp = 0;
  odometry::TrackingState state = odometry::TrackingState::kLost;
  Eigen::Isometry3d T_world_camera = Eigen::Isometry3d::Identity();  // as tracked (online)
  std::int64_t reference_keyframe = -1;
  Eigen::Isometry3d T_keyframe_camera = Eigen::Isometry3d::Identity();
  bool is_keyframe = false;
  int inliers = 0;   // map points tracked
  std::string note;  // the tracker's reason: why weak/lost, why a keyframe
  FrameTiming timing;
};

// The whole odometry in one thread, frame by frame: rectify, extract, track, and on a keyframe
// run the windowed bundle adjustment and hand its update back to the tracker. The same input
// gives the same output. The clock (milliseconds) is only read to fill FrameTiming.
class StereoOdometry {
 public:
  using Clock = std::function<double()>;

  StereoOdometry(const PipelineOptions& options, const camera::StereoRectifier& rectifier,
                 Clock clock);

  // Raw (unrectified) mono8 images of one stereo pair.
  const FrameRecord& ProcessFrame(double timestamp, const cv::Mat& left_raw,
                                  const cv::Mat& right_raw);

  // Every frame's rectified left camera pose, through its keyframe's latest optimised pose.
  evaluation::Trajectory CameraTrajectory() const;
  evaluation::Trajectory KeyframeTrajectory() const;
  const std::vector<FrameRecord>& frames() const { return frames_; }
  std::size_t keyframe_count() const { return keyframe_times_.size(); }

 private:
  const camera::StereoRectifier& rectifier_;
  Clock clock_;
  features::StereoFeatureExtractor extractor_;
  odometry::Tracker tracker_;
  backend::LocalBundleAdjuster bundle_adjuster_;
  std::vector<FrameRecord> frames_;
  std::map<std::int64_t, double> keyframe_times_;
};

}  // namespace stereo_fabmap_slam::pipeline
