#pragma once

#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include <opencv2/core.hpp>

#include "stereo_fabmap_slam/camera/stereo_rectifier.h"
#include "stereo_fabmap_slam/io/option_reader.h"
#include "stereo_fabmap_slam/io/trajectory.h"
#include "stereo_fabmap_slam/pipeline/backend.h"
#include "stereo_fabmap_slam/pipeline/loop_closing.h"
#include "stereo_fabmap_slam/pipeline/relocalization.h"
#include "stereo_fabmap_slam/pipeline/stereo_front_end.h"

namespace stereo_fabmap_slam::pipeline {

// Mapping extends the map with every keyframe; localization tracks against a map (loaded from a
// file) without changing it: the odometry runs as always, and relocalizations against the map
// (at start, after every loss, and at each of the odometry's keyframes) give map -> odom.
enum class SlamMode { kMapping, kLocalization };
inline constexpr io::EnumName<SlamMode> kSlamModeNames[] = {
    {SlamMode::kMapping, "mapping"}, {SlamMode::kLocalization, "localization"}};

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
  // Whether the frame had a pose in the map when it was processed: false while tracking is lost
  // and while the odometry runs in a piece of map not (yet) found in the map (after a loss).
  bool on_map = true;
  std::optional<RelocalizationOutput> relocalization;  // an attempt on this frame
  // Localization mode: the frame's pose in the map when it was processed (map -> odom of the
  // latest relocalization times the odometry).
  std::optional<Eigen::Isometry3d> T_map_camera;
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

  // Turns loop closing and relocalization on (before the first frame). The front end must make
  // place descriptors (FrontEndOptions::place_features). After a tracking loss every n-th frame
  // (relocalizer_options.attempt_every_n_frames) is relocalized against the map until one is
  // found; its relocalization edge joins the new piece of odometry to the map.
  void EnableLoopClosing(place_recognition::LoopDetector detector,
                         const backend::PoseGraphOptions& pose_graph_options,
                         const relocalization::RelocalizerOptions& relocalizer_options = {});
  void SetMode(SlamMode mode) { mode_ = mode; }
  // The map (keyframes, words, pose graph) to a file, and back. Loading replaces the map after
  // checking the file, its vocabulary and its camera (io::InputError says what is wrong; the
  // running map stays as it was). After a load the odometry goes on in a piece of its own until
  // a relocalization finds it in the loaded map. Loop closing must be on.
  void SaveMap(const std::string& path) const;
  void LoadMap(const std::string& path);
  SlamMode mode() const { return mode_; }

  // Raw (unrectified) mono8 images of one stereo pair; `frames_skipped` stereo pairs were passed
  // over since the last one processed (a caller that cannot keep up: Tracker::Track).
  const FrameRecord& ProcessFrame(double timestamp, const cv::Mat& left_raw,
                                  const cv::Mat& right_raw, int frames_skipped = 0);

  // Relocalizes a stereo pair against the whole map without tracking it or changing anything
  // (the relocalize service's check of a view). Loop closing must be on.
  RelocalizationOutput Relocalize(const cv::Mat& left_raw, const cv::Mat& right_raw) const;

  // Every frame's rectified left camera pose, through its keyframe's latest optimised pose: in
  // odom (the odometry, without loop closing) and in map (after loop closing; the same as the
  // odometry while no loop was closed or loop closing is off). The map trajectory holds the
  // frames that have a pose in the map: not those of a piece of odometry never found in it.
  io::Trajectory OdometryTrajectory() const;
  io::Trajectory MapTrajectory() const;
  io::Trajectory KeyframeTrajectory() const;
  const std::vector<FrameRecord>& frames() const { return frames_; }
  double KeyframeTime(std::int64_t id) const { return keyframe_times_.at(id); }
  int descriptor_norm() const { return front_end_.descriptor_norm(); }
  double max_match_distance() const { return front_end_.max_match_distance(); }
  std::size_t keyframe_count() const { return keyframe_times_.size(); }
  const LoopClosing* map() const { return loop_closing_ ? &*loop_closing_ : nullptr; }

 private:
  // Mapping: while the frame's piece of odometry is not joined to the map, relocalize it.
  void RecoverIntoMap(const FrontEndOutput& output, FrameRecord* record);
  // Localization: relocalize until found, then at every keyframe; map -> odom from the latest.
  void Localize(const FrontEndOutput& output, FrameRecord* record);
  RelocalizationOutput RelocalizeFrame(const FrontEndOutput& output,
                                       const relocalization::Relocalizer::KeyframeFilter& allowed);

  Clock clock_;
  StereoFrontEnd front_end_;
  Backend backend_;
  std::optional<LoopClosing> loop_closing_;
  std::optional<RelocalizationStage> relocalization_;
  SlamMode mode_ = SlamMode::kMapping;
  std::int64_t anchor_ = -1;  // the map's first keyframe: "in the map" is connected to it
  int frames_off_map_ = 0;    // since the last attempt's cycle began (every n-th attempts)
  bool localized_ = false;    // localization mode: T_map_odom_ is valid
  Eigen::Isometry3d T_map_odom_ = Eigen::Isometry3d::Identity();
  std::vector<FrameRecord> frames_;
  std::map<std::int64_t, double> keyframe_times_;
};

}  // namespace stereo_fabmap_slam::pipeline
