#pragma once

#include <cstdint>
#include <optional>
#include <string>

#include <Eigen/Geometry>

#include "stereo_fabmap_slam/odometry/tracker.h"
#include "stereo_fabmap_slam/pipeline/place_stage.h"
#include "stereo_fabmap_slam/pipeline/slam_mode.h"
#include "stereo_fabmap_slam/relocalization/relocalization_options.h"

namespace stereo_fabmap_slam::pipeline {

// What the relocalize service answers its caller.
struct UserRelocalization {
  bool success = false;
  std::string message;
  Eigen::Isometry3d T_map_camera = Eigen::Isometry3d::Identity();  // meaningful on success
  std::int64_t keyframe_id = -1;
  int inliers = 0;
  double probability = 0;
  double time_ms = 0;
};

// What a relocalization answer changed.
struct RelocalizationOutcome {
  // Localization mode: map -> odom from this relocalization (the mapping stage's, and tf's).
  std::optional<Eigen::Isometry3d> T_map_odom;
  std::string news;  // worth a line in the log (found again, localized); may be empty
  std::optional<UserRelocalization> user;  // the answer to the user's request, if it was one
};

// When the tracking stage asks the place stage to find the camera in the map, and what it makes
// of the answer. Mapping: a break of the odometry (a tracking loss that starts a new segment, a
// reset, a loaded map, the end of localization mode) while the map has keyframes starts a
// recovery: every n-th frame with a pose is relocalized against the map's keyframes only; the
// first success is a candidate, and the first success from a camera confirm_distance (straight
// line, odometry) from it that agrees with it joins the frame's segment to the map with a
// relocalization edge (one that disagrees becomes the candidate instead); or a loop joined it
// (the frame's keyframe is in the map, or the place stage says so). Localization: relocalized until
// found, then at every keyframe; each success gives map -> odom. A user's request (the relocalize
// service) is answered by the next frame: a check of the view, which corrects map -> odom only if
// asked to re-anchor. No clock, no thread.
class RelocalizationPolicy {
 public:
  // Reads attempt_every_n_frames and confirm_distance (0: the first success joins).
  explicit RelocalizationPolicy(const relocalization::RelocalizerOptions& options);

  void SetMode(SlamMode mode, bool map_has_keyframes);
  void OnMapLoaded();
  // The next break of the odometry comes from time going backwards, not a loss.
  void OnReset() { break_reason_ = "time went backwards"; }
  void RequestFromUser(bool reanchor);
  // The user gave up on the request before a frame answered it.
  void CancelUserRequest() { user_request_.reset(); }
  bool user_request_pending() const { return user_request_.has_value(); }

  struct Decision {
    bool ask = false;  // make a RelocalizationRequest with the fields below
    RelocalizationRequest::Scope scope = RelocalizationRequest::Scope::kAnywhere;
    bool add_edge = false;
    // Recovery with a candidate: where its map -> odom puts this frame's camera.
    std::optional<Eigen::Isometry3d> expected_T_map_camera;
    bool from_user = false;
    // A relocalization was due or asked for, but the frame has no pose to give (lost): why.
    std::string failure;
  };
  // After the tracker's result for a frame: whether (and how) to ask the place stage.
  // `reference_in_map`: the map holds the frame's reference keyframe, i.e. a loop has joined the
  // frame's segment to the map (recovery then ends without asking).
  Decision Decide(const odometry::TrackingResult& result, bool map_has_keyframes,
                  bool reference_in_map = false);
  RelocalizationOutcome OnAnswer(const RelocalizationRequest& request,
                                 const RelocalizationAnswer& answer);
  // The user's request could not be asked (Decision::failure): its answer.
  UserRelocalization FailUserRequest(const std::string& failure);
  // The place stage could not be asked (a driver whose place stage is not running): the
  // recovery tries again at its next due frame; a user's request is answered with `reason`.
  RelocalizationOutcome OnNoAnswer(const RelocalizationRequest& request, const std::string& reason);

  // Whether the last frame had a pose in the map: mapping, its segment is in the map;
  // localization, map -> odom is known. And that pose (localization; T_map_odom * the odometry).
  bool on_map() const;
  std::optional<Eigen::Isometry3d> T_map_camera() const;
  SlamMode mode() const { return mode_; }
  bool recovering() const { return recovering_; }

 private:
  int every_;
  double confirm_distance_;
  SlamMode mode_ = SlamMode::kMapping;
  bool recovering_ = false;  // mapping: the odometry's segment is not in the map
  bool localized_ = false;   // localization: T_map_odom_ holds
  Eigen::Isometry3d T_map_odom_ = Eigen::Isometry3d::Identity();
  int frames_since_attempt_ = 0;
  std::string break_reason_ = "tracking loss";
  // Mapping recovery: the first success of the segment, awaiting a second from elsewhere.
  struct Candidate {
    Eigen::Isometry3d T_map_odom = Eigen::Isometry3d::Identity();
    Eigen::Vector3d odom_position = Eigen::Vector3d::Zero();  // of the camera it was found from
    std::int64_t keyframe_id = -1;
  };
  std::optional<Candidate> candidate_;
  struct UserRequest {
    bool reanchor = false;
  };
  std::optional<UserRequest> user_request_;
  // The last frame's, for on_map() and T_map_camera().
  std::int64_t reference_keyframe_ = -1;
  Eigen::Isometry3d T_odom_camera_ = Eigen::Isometry3d::Identity();
  bool has_pose_ = false;
};

}  // namespace stereo_fabmap_slam::pipeline
