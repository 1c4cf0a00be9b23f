#pragma once

#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include <opencv2/core.hpp>

#include "stereo_fabmap_slam/camera/stereo_rectifier.h"
#include "stereo_fabmap_slam/evaluation/trajectory.h"
#include "stereo_fabmap_slam/pipeline/backend.h"
#include "stereo_fabmap_slam/pipeline/loop_closing.h"
#include "stereo_fabmap_slam/pipeline/stereo_front_end.h"

namespace stereo_fabmap_slam::pipeline {

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
  std::optional<place_recognition::LoopDetection> loop_detection;  // keyframes, loop closing on
};

// The whole SLAM in one thread, frame by frame, through the stages the nodelets run apart:
// the front end; on a keyframe the backend (windowed bundle adjustment), whose update goes
// straight back to the tracker; then, if enabled, loop closing (FAB-MAP, verification, pose
// graph). The same input gives the same output. The clock (milliseconds) is only read to fill
// FrameTiming.
class StereoSlam {
 public:
  using Clock = StereoFrontEnd::Clock;

  StereoSlam(const FrontEndOptions& front_end_options,
             const backend::BundleAdjustmentOptions& bundle_adjustment_options,
             const camera::StereoRectifier& rectifier, Clock clock);

  // Turns loop closing on (before the first frame). The front end must make place descriptors
  // (FrontEndOptions::place_features).
  void EnableLoopClosing(place_recognition::LoopDetector detector,
                         const backend::PoseGraphOptions& pose_graph_options);

  // Raw (unrectified) mono8 images of one stereo pair.
  const FrameRecord& ProcessFrame(double timestamp, const cv::Mat& left_raw,
                                  const cv::Mat& right_raw);

  // Every frame's rectified left camera pose, through its keyframe's latest optimised pose: in
  // odom (the odometry, without loop closing) and in map (after loop closing; the same as the
  // odometry while no loop was closed or loop closing is off).
  evaluation::Trajectory OdometryTrajectory() const;
  evaluation::Trajectory MapTrajectory() const;
  evaluation::Trajectory KeyframeTrajectory() const;
  const std::vector<FrameRecord>& frames() const { return frames_; }
  double KeyframeTime(std::int64_t id) const { return keyframe_times_.at(id); }
  int descriptor_norm() const { return front_end_.descriptor_norm(); }
  double max_match_distance() const { return front_end_.max_match_distance(); }
  std::size_t keyframe_count() const { return keyframe_times_.size(); }

 private:
  Clock clock_;
  StereoFrontEnd front_end_;
  Backend backend_;
  std::optional<LoopClosing> loop_closing_;
  std::vector<FrameRecord> frames_;
  std::map<std::int64_t, double> keyframe_times_;
};

}  // namespace stereo_fabmap_slam::pipeline
