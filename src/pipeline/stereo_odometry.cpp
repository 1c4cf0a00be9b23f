#include "stereo_fabmap_slam/pipeline/stereo_odometry.h"

namespace stereo_fabmap_slam::pipeline {

StereoOdometry::StereoOdometry(const PipelineOptions& options,
                               const camera::StereoRectifier& rectifier, Clock clock)
    : rectifier_(rectifier),
      clock_(std::move(clock)),
      extractor_(options.features, options.stereo, rectifier.camera()),
      tracker_(options.tracker, options.keyframes, rectifier.camera(), extractor_.descriptor_norm(),
               extractor_.max_match_distance()),
      bundle_adjuster_(options.backend, rectifier.camera()) {}

const FrameRecord& StereoOdometry::ProcessFrame(double timestamp, const cv::Mat& left_raw,
                                                const cv::Mat& right_raw) {
  FrameRecord record;
  record.timestamp = timestamp;
  FrameTiming& timing = record.timing;
  double start = clock_();
  const auto lap = [&](double* stage) {
    const double now = clock_();
    *stage = now - start;
    start = now;
  };
  cv::Mat left, right;
  rectifier_.Rectify(left_raw, right_raw, &left, &right);
  lap(&timing.rectification_ms);
  features::StereoFeatureExtractor::Detected detected = extractor_.Detect(left, right);
  lap(&timing.detection_ms);
  features::StereoFeatureExtractor::Described described =
      extractor_.Describe(left, right, std::move(detected));
  lap(&timing.description_ms);
  features::StereoFeatures features = extractor_.Match(left, right, std::move(described));
  lap(&timing.stereo_ms);
  odometry::TrackingResult result = tracker_.Track(timestamp, std::move(features));
  lap(&timing.tracking_ms);
  if (result.keyframe) {
    keyframe_times_[result.keyframe->id] = timestamp;
    tracker_.ApplyUpdate(bundle_adjuster_.AddKeyframe(*result.keyframe));
    lap(&timing.bundle_adjustment_ms);
  }
  record.state = result.state;
  record.T_world_camera = result.T_world_camera;
  record.reference_keyframe = result.reference_keyframe;
  record.T_keyframe_camera = result.T_keyframe_camera;
  record.is_keyframe = result.keyframe.has_value();
  record.inliers = result.inliers;
  record.note = result.reason;
  frames_.push_back(record);
  return frames_.back();
}

evaluation::Trajectory StereoOdometry::CameraTrajectory() const {
  const std::map<std::int64_t, Eigen::Isometry3d> keyframes = bundle_adjuster_.KeyframePoses();
  evaluation::Trajectory trajectory;
  for (const FrameRecord& frame : frames_) {
    const auto keyframe = keyframes.find(frame.reference_keyframe);
    trajectory.push_back({frame.timestamp, keyframe == keyframes.end()
                                               ? frame.T_world_camera
                                               : keyframe->second * frame.T_keyframe_camera});
  }
  return trajectory;
}

evaluation::Trajectory StereoOdometry::KeyframeTrajectory() const {
  evaluation::Trajectory trajectory;
  for (const auto& [id, pose] : bundle_adjuster_.KeyframePoses()) {
    trajectory.push_back({keyframe_times_.at(id), pose});
  }
  return trajectory;
}

}  // namespace stereo_fabmap_slam::pipeline
