#pragma once

#include <algorithm>
#include <array>
#include <cstddef>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include <Eigen/Geometry>
#include <opencv2/core/types.hpp>

#include "stereo_fabmap_slam/concurrency/helper_thread.h"
#include "stereo_fabmap_slam/features/stereo_features.h"
#include "stereo_fabmap_slam/geometry/pnp_ransac.h"
#include "stereo_fabmap_slam/geometry/pose_refiner.h"
#include "stereo_fabmap_slam/geometry/stereo_camera.h"
#include "stereo_fabmap_slam/io/option_reader.h"
#include "stereo_fabmap_slam/map/keyframe.h"
#include "stereo_fabmap_slam/map/keyframe_update.h"
#include "stereo_fabmap_slam/odometry/keyframe_policy.h"
#include "stereo_fabmap_slam/odometry/local_map.h"
#include "stereo_fabmap_slam/odometry/odometry_options.h"

namespace stereo_fabmap_slam::odometry {

enum class TrackingState { kOk, kWeak, kLost };
const char* TrackingStateName(TrackingState state);

struct TrackingResult {
  TrackingState state = TrackingState::kLost;
  std::string reason;  // why weak or lost; what happened otherwise
  Eigen::Isometry3d T_world_camera = Eigen::Isometry3d::Identity();
  int matches = 0;  // map points found in the frame
  int inliers = 0;  // of those, consistent with the pose
  // Of T_world_camera (right perturbation, translation then rotation): how well this frame's
  // inliers pin the pose down relative to the local map (geometry::StereoPoseCovariance); 1e6
  // on the diagonal where the pose is not an estimate (the first frame of a new segment).
  geometry::PoseCovariance covariance = geometry::PoseCovariance::Identity();
  // The pose relative to a keyframe, so that the trajectory follows later keyframe corrections.
  std::int64_t reference_keyframe = -1;
  Eigen::Isometry3d T_keyframe_camera = Eigen::Isometry3d::Identity();
  std::optional<map::Keyframe> keyframe;  // set if this frame became a keyframe
  // Lost, but the local map is kept for the next frames (TrackerOptions::max_time_lost): the
  // odometry goes on where it was if one of them is tracked. T_world_camera is the motion
  // model's guess, not an estimate.
  bool map_kept = false;
  // The frame's key points by what tracking made of them, for display (rectified left image):
  // matched to map points and consistent with the pose; matched but rejected as outliers; the
  // others with stereo depth (the new points of a keyframe, candidates otherwise).
  std::vector<cv::Point2f> inlier_pixels, outlier_pixels, untracked_pixels;
};

// Frame-to-map tracking: predicts the pose with a constant-velocity model, finds local map points
// in the frame by projection and descriptor, estimates the pose with RANSAC (a selectable
// kernel) and refines it with a robust motion-only optimisation, searches again around the
// refined projections, and decides on keyframes. When the prediction finds too little, the frame
// is matched to the local map by descriptor alone before tracking is declared lost.
// Deterministic for a given input sequence.
class Tracker {
 public:
  // Throws std::invalid_argument for bad options. helper: shares the search of the map points
  // with the calling thread if options.parallel (null: the calling thread alone; the same
  // result either way).
  Tracker(const TrackerOptions& options, const KeyframePolicyOptions& keyframe_options,
          const geometry::StereoCamera& camera, int descriptor_norm, double max_descriptor_distance,
          concurrency::HelperThread* helper = nullptr);

  // `frames_skipped`: camera frames the caller passed over since the last frame it gave to
  // Track (a tracker that cannot keep up); keyframes are then taken before the bounds are
  // crossed in the frames it will skip next (KeyframePolicyInput::before_next_frame).
  TrackingResult Track(double timestamp, features::StereoFeatures features, int frames_skipped = 0);
  // Optimised keyframe poses and points from the backend.
  void ApplyUpdate(const map::KeyframeUpdate& update);
  // Forget the local map and the motion (e.g. time went backwards); the next frame starts a new
  // segment.
  void Reset();
  // Forget the local map but not the motion: the next frame starts a new local map where the
  // odometry predicts it, so odom stays continuous (e.g. after a map was loaded whose keyframe
  // ids the local map's may share).
  void StartNewLocalMap() { local_map_.Clear(); }
  // Where the camera is at the first frame (and after Reset): the odometry frame's origin is
  // then not the first camera but, e.g., the robot's base (T_odom_camera = the camera's
  // mounting T_base_camera, REP-105's odom). Identity by default: odom is the first camera.
  void SetStartPose(const Eigen::Isometry3d& T_odom_camera) { start_pose_ = T_odom_camera; }
  // New keyframes and map points get ids of at least these (a loaded map holds the lower ones).
  void SkipIdsBelow(std::int64_t keyframe_id, std::int64_t point_id) {
    next_keyframe_id_ = std::max(next_keyframe_id_, keyframe_id);
    next_point_id_ = std::max(next_point_id_, point_id);
  }

 private:
  struct Match {
    const MapPoint* point;
    int keypoint;
    double distance;
  };

  std::vector<Match> SearchByProjection(const features::StereoFeatures& features,
                                        const Eigen::Isometry3d& T_camera_world,
                                        double radius) const;
  // Every local map point against every key point, by descriptor and ratio test: no pose needed.
  std::vector<Match> SearchByDescriptor(const features::StereoFeatures& features) const;
  geometry::PnpResult SolvePose(const features::StereoFeatures& features,
                                const std::vector<Match>& matches,
                                const geometry::PnpRansacOptions& ransac_options,
                                const Eigen::Isometry3d& guess) const;
  std::vector<geometry::PoseObservation> Observations(const features::StereoFeatures& features,
                                                      const std::vector<Match>& matches) const;
  map::Keyframe MakeKeyframe(double timestamp, features::StereoFeatures features,
                             const Eigen::Isometry3d& T_world_camera,
                             const std::vector<Match>& inlier_matches, bool starts_new_segment);
  void StartMap(double timestamp, features::StereoFeatures features,
                const Eigen::Isometry3d& T_world_camera, TrackingResult* result);
  // The exit of a frame that could not be tracked against a map (there is none, or tracking
  // failed): a new segment starts at the predicted pose if the frame has enough stereo points, and
  // the frame is lost otherwise.
  TrackingResult StartOver(double timestamp, features::StereoFeatures features,
                           const Eigen::Isometry3d& predicted, TrackingResult result);
  // The exit of a frame that failed against the local map with a RANSAC consensus of
  // `consensus` points: the map is kept if that still shows the map and the last tracked frame
  // is within max_time_lost, and StartOver follows otherwise.
  TrackingResult Lose(double timestamp, features::StereoFeatures features,
                      const Eigen::Isometry3d& predicted, int consensus, TrackingResult result);
  void Remember(double timestamp, const Eigen::Isometry3d& T_world_camera, TrackingResult* result);
  // Whether a pose found by descriptor, `jump` from the prediction, may be taken: near the
  // prediction always; farther only with relocalization's evidence (TrackerOptions::
  // max_descriptor_jump), the inliers of `result` counted and their spread over the image.
  bool EnoughToJump(const Eigen::Isometry3d& jump, const TrackingResult& result) const;
  // What the keyframe policy decides on for a frame tracked at `T_world_camera`; updates the
  // ratio rule's reference.
  KeyframePolicyInput KeyframeInput(double timestamp, const Eigen::Isometry3d& T_world_camera,
                                    const TrackingResult& result, int settled_points);
  // The constant-velocity prediction for a frame at `timestamp`.
  Eigen::Isometry3d Predict(double timestamp) const;

  TrackerOptions options_;
  KeyframePolicy keyframe_policy_;
  geometry::StereoCamera camera_;
  geometry::PnpRansacOptions ransac_options_;
  geometry::PnpRansacOptions ransac_options_without_prior_;
  int descriptor_norm_;
  double max_descriptor_distance_;
  concurrency::HelperThread* helper_;  // not owned; may be null

  LocalMap local_map_;
  std::int64_t next_keyframe_id_ = 0;
  std::int64_t next_point_id_ = 0;
  bool had_map_ = false;

  bool has_last_ = false;
  Eigen::Isometry3d start_pose_ = Eigen::Isometry3d::Identity();
  Eigen::Isometry3d last_T_world_camera_ = Eigen::Isometry3d::Identity();
  Eigen::Isometry3d velocity_ = Eigen::Isometry3d::Identity();  // T_previous_current
  double last_timestamp_ = 0;
  double velocity_dt_ = 0;  // [s] the time velocity_ spans; 0: unknown
  Eigen::Isometry3d last_keyframe_pose_ = Eigen::Isometry3d::Identity();
  double last_keyframe_time_ = 0;
  // Points with lower ids are older than the last keyframe (settled, KeyframeMeasures).
  std::int64_t first_point_of_last_keyframe_ = 0;
  int most_settled_since_keyframe_ = 0;
  int last_settled_points_ = 0;  // in the last frame tracked (or keyframe)
  // Camera frames since the last tracked frame, this one included: those the caller skipped
  // and those lost with the map kept (Track's frames_skipped).
  int frames_since_tracked_ = 0;
  // Track's frames_skipped over the last frames; the largest is the guess of how many the caller
  // skips before the next one. A tracker slower than the camera by a fraction skips a varying
  // number (FrameQueue at 5x: none for most pairs, then one or more after a slow frame), so
  // guessing the last count misses the bounds crossed in the longer gaps that follow shorter
  // ones, and takes their keyframes a gap late. Through the graph at 5x (MH01_first10s, ~10 of
  // 200 pairs skipped) that made 25 keyframes against 26 at 1x in 2 of 10 runs; with the largest
  // of the last four, 23 of 23 runs made 26-41. Erring this way takes a keyframe at most a gap
  // early, and costs keyframes only while pairs are skipped (every 2.3rd pair offline: MH01 37
  // against 28, the rendered figure eight 201 against 156; 26 and 143 at every pair). Four
  // frames hold both counts of an alternation and let a burst go after about a tenth of a
  // second at 5x.
  static constexpr std::size_t kSkipHistory = 4;
  std::array<int, kSkipHistory> recent_frames_skipped_{};
  std::size_t next_skip_slot_ = 0;
};

}  // namespace stereo_fabmap_slam::odometry
