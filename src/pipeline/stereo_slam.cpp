#include "stereo_fabmap_slam/pipeline/stereo_slam.h"

namespace stereo_fabmap_slam::pipeline {

StereoSlam::StereoSlam(const FrontEndOptions& front_end_options,
                       const backend::BundleAdjustmentOptions& bundle_adjustment_options,
                       const camera::StereoRectifier& rectifier, Clock clock)
    : clock_(clock),
      front_end_(front_end_options, rectifier, clock),
      backend_(bundle_adjustment_options, rectifier.camera(), clock) {}

const FrameRecord& StereoSlam::ProcessFrame(double timestamp, const cv::Mat& left_raw,
                                            const cv::Mat& right_raw) {
  FrontEndOutput output = front_end_.Process(timestamp, left_raw, right_raw);
  const odometry::TrackingResult& result = output.tracking;
  FrameRecord record;
  record.timestamp = timestamp;
  record.timing = output.timing;
  if (result.keyframe) {
    keyframe_times_[result.keyframe->id] = timestamp;
    const BackendOutput adjusted = backend_.Process(*result.keyframe);
    front_end_.ApplyUpdate(adjusted.update);
    record.timing.bundle_adjustment_ms = adjusted.bundle_adjustment_ms;
    if (loop_closing_) {
      LoopClosingOutput closing = loop_closing_->Process(*result.keyframe, adjusted.update);
      record.timing.loop_detection_ms = closing.detection_ms;
      record.timing.pose_graph_ms = closing.pose_graph_ms;
      record.loop_detection = std::move(closing.detection);
    }
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

evaluation::Trajectory StereoSlam::OdometryTrajectory() const {
  const std::map<std::int64_t, Eigen::Isometry3d> keyframes = backend_.KeyframePoses();
  evaluation::Trajectory trajectory;
  for (const FrameRecord& frame : frames_) {
    const auto keyframe = keyframes.find(frame.reference_keyframe);
    trajectory.push_back({frame.timestamp, keyframe == keyframes.end()
                                               ? frame.T_world_camera
                                               : keyframe->second * frame.T_keyframe_camera});
  }
  return trajectory;
}

void StereoSlam::EnableLoopClosing(place_recognition::LoopDetector detector,
                                   const backend::PoseGraphOptions& pose_graph_options) {
  loop_closing_.emplace(std::move(detector), pose_graph_options, clock_);
}

evaluation::Trajectory StereoSlam::MapTrajectory() const {
  if (!loop_closing_) return OdometryTrajectory();
  const backend::PoseGraph& graph = loop_closing_->pose_graph();
  evaluation::Trajectory trajectory;
  for (const FrameRecord& frame : frames_) {
    if (graph.Contains(frame.reference_keyframe)) {
      trajectory.push_back(
          {frame.timestamp, graph.MapPose(frame.reference_keyframe) * frame.T_keyframe_camera});
    } else {
      // Before the first keyframe: the odometry's pose, moved by the map's current correction.
      trajectory.push_back({frame.timestamp, graph.MapToOdom() * frame.T_world_camera});
    }
  }
  return trajectory;
}

evaluation::Trajectory StereoSlam::KeyframeTrajectory() const {
  evaluation::Trajectory trajectory;
  const std::map<std::int64_t, Eigen::Isometry3d> poses =
      loop_closing_ ? loop_closing_->pose_graph().MapPoses() : backend_.KeyframePoses();
  for (const auto& [id, pose] : poses) {
    trajectory.push_back({keyframe_times_.at(id), pose});
  }
  return trajectory;
}

}  // namespace stereo_fabmap_slam::pipeline
