#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include <Eigen/Geometry>

#include "stereo_fabmap_slam/camera/stereo_camera.h"
#include "stereo_fabmap_slam/features/stereo_features.h"
#include "stereo_fabmap_slam/geometry/pnp_ransac.h"
#include "stereo_fabmap_slam/io/option_reader.h"
#include "stereo_fabmap_slam/odometry/keyframe_data.h"
#include "stereo_fabmap_slam/odometry/keyframe_policy.h"
#include "stereo_fabmap_slam/odometry/local_map.h"
#include "stereo_fabmap_slam/odometry/pose_refiner.h"

namespace stereo_fabmap_slam::odometry {

struct TrackerOptions {
  double search_radius = 15.0;      // [px] around a map point's predicted projection
  double search_radius_fine = 4.0;  // [px] second search, around the refined pose's projection
  double match_ratio = 0.85;        // best / second-best descriptor distance
  std::string pnp_kernel = "AP3P";  // ITERATIVE, EPNP, AP3P, P3P, SQPNP, UMEYAMA
  double ransac_threshold = 2.0;    // [px]
  int ransac_iterations = 100;
  int min_inliers_ok = 50;    // fewer inliers: tracking weak
  int min_inliers_weak = 15;  // fewer inliers: tracking lost
  int min_map_points = 30;    // stereo points needed to start a map
  int local_keyframes = 16;   // recent keyframes whose points the tracker searches
  bool parallel = true;       // search map points on two threads
  PoseRefinementOptions refinement;

  void Visit(io::OptionVisitor& visitor);
  void Validate() const;
};

enum class TrackingState { kOk, kWeak, kLost };
const char* TrackingStateName(TrackingState state);

struct TrackingResult {
  TrackingState state = TrackingState::kLost;
  std::string reason;  // why weak or lost; what happened otherwise
  Eigen::Isometry3d T_world_camera = Eigen::Isometry3d::Identity();
  int matches = 0;  // map points found in the frame
  int inliers = 0;  // of those, consistent with the pose
  // The pose relative to a keyframe, so that the trajectory follows later keyframe corrections.
  std::int64_t reference_keyframe = -1;
  Eigen::Isometry3d T_keyframe_camera = Eigen::Isometry3d::Identity();
  std::optional<KeyframeData> keyframe;  // set if this frame became a keyframe
};

// Frame-to-map tracking: predicts the pose with a constant-velocity model, finds local map points
// in the frame by projection and descriptor, estimates the pose with RANSAC (a selectable
// kernel) and refines it with a robust motion-only optimisation, searches again around the
// refined projections, and decides on keyframes. Deterministic for a given input sequence.
class Tracker {
 public:
  // Throws std::invalid_argument for bad options.
  Tracker(const TrackerOptions& options, const KeyframePolicyOptions& keyframe_options,
          const camera::StereoCamera& camera, int descriptor_norm, double max_descriptor_distance);

  TrackingResult Track(double timestamp, features::StereoFeatures features);
  // Optimised keyframe poses and points from the backend.
  void ApplyUpdate(const KeyframeUpdate& update);
  // Forget the map and the motion (e.g. time went backwards); the next frame starts a new map.
  void Reset();

 private:
  struct Match {
    const MapPoint* point;
    int keypoint;
    double distance;
  };

  std::vector<Match> SearchByProjection(const features::StereoFeatures& features,
                                        const Eigen::Isometry3d& T_camera_world,
                                        double radius) const;
  std::vector<PoseObservation> Observations(const features::StereoFeatures& features,
                                            const std::vector<Match>& matches) const;
  KeyframeData MakeKeyframe(double timestamp, features::StereoFeatures features,
                            const Eigen::Isometry3d& T_world_camera,
                            const std::vector<Match>& inlier_matches, bool starts_new_map);
  void StartMap(double timestamp, features::StereoFeatures features,
                const Eigen::Isometry3d& T_world_camera, TrackingResult* result);
  void Remember(double timestamp, const Eigen::Isometry3d& T_world_camera, TrackingResult* result);

  TrackerOptions options_;
  KeyframePolicy keyframe_policy_;
  camera::StereoCamera camera_;
  geometry::PnpRansacOptions ransac_options_;
  int descriptor_norm_;
  double max_descriptor_distance_;

  LocalMap local_map_;
  std::int64_t next_keyframe_id_ = 0;
  std::int64_t next_point_id_ = 0;
  bool had_map_ = false;

  bool has_last_ = false;
  double last_timestamp_ = 0;
  Eigen::Isometry3d last_T_world_camera_ = Eigen::Isometry3d::Identity();
  Eigen::Isometry3d velocity_ = Eigen::Isometry3d::Identity();  // T_previous_current
  Eigen::Isometry3d last_keyframe_pose_ = Eigen::Isometry3d::Identity();
  double last_keyframe_time_ = 0;
  int most_tracked_since_keyframe_ = 0;
};

}  // namespace stereo_fabmap_slam::odometry
