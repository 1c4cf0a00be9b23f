#include "stereo_fabmap_slam/pipeline/relocalization_policy.h"

#include <stdexcept>

namespace stereo_fabmap_slam::pipeline {
namespace {

std::string FoundText(const relocalization::Relocalization& found) {
  return "keyframe " + std::to_string(found.keyframe_id) + " (" + std::to_string(found.inliers) +
         " inliers)";
}

}  // namespace

RelocalizationPolicy::RelocalizationPolicy(const relocalization::RelocalizerOptions& options)
    : every_(options.attempt_every_n_frames), confirm_distance_(options.confirm_distance) {
  if (every_ < 1) throw std::invalid_argument("relocalization: attempt every n >= 1 frames");
  if (!(confirm_distance_ >= 0))
    throw std::invalid_argument("relocalization: confirm_distance must be >= 0");
}

void RelocalizationPolicy::SetMode(SlamMode mode, bool map_has_keyframes) {
  // Back to mapping: the odometry goes on in a new segment (the mapping stage starts one), which
  // a relocalization joins to the map.
  if (mode_ == SlamMode::kLocalization && mode == SlamMode::kMapping) {
    recovering_ = map_has_keyframes;
    break_reason_ = "localization mode";
  }
  if (mode != mode_) candidate_.reset();
  mode_ = mode;
  localized_ = false;
  frames_since_attempt_ = 0;
}

void RelocalizationPolicy::OnMapLoaded() {
  // The odometry so far is another map's: it is not in the loaded map until found there.
  recovering_ = mode_ == SlamMode::kMapping;
  break_reason_ = "loading a map";
  localized_ = false;
  frames_since_attempt_ = 0;
  candidate_.reset();
}

void RelocalizationPolicy::RequestFromUser(bool reanchor) { user_request_ = UserRequest{reanchor}; }

RelocalizationPolicy::Decision RelocalizationPolicy::Decide(const odometry::TrackingResult& result,
                                                            bool map_has_keyframes,
                                                            bool reference_in_map) {
  Decision decision;
  // A new segment (after a loss, or a reset) is not in the map until a relocalization (or a
  // loop) joins it. A lost frame whose map the tracker kept has no pose, but the odometry goes on
  // unbroken if a later frame is tracked; if none is, a new segment follows.
  const bool new_segment = result.keyframe && result.keyframe->starts_new_segment;
  const bool broken =
      new_segment || (result.state == odometry::TrackingState::kLost && !result.map_kept);
  if (mode_ == SlamMode::kLocalization) {
    if (broken) localized_ = false;  // the old map -> odom no longer holds
  } else if (broken && map_has_keyframes) {
    if (!recovering_) frames_since_attempt_ = 0;
    recovering_ = true;
    candidate_.reset();  // its map -> odom was for the odometry before the break
  } else if (recovering_ && reference_in_map && result.state != odometry::TrackingState::kLost) {
    // A loop joined the segment meanwhile (the place stage would answer "joined already").
    recovering_ = false;
    candidate_.reset();
    break_reason_ = "tracking loss";
  }
  // A lost frame without a new keyframe has only the motion model's guess: nothing to find.
  has_pose_ = result.state != odometry::TrackingState::kLost || result.keyframe.has_value();
  reference_keyframe_ = result.reference_keyframe;
  T_odom_camera_ = result.T_world_camera;
  // A candidate is confirmed only from a view elsewhere (RelocalizerOptions::confirm_distance).
  const bool far_from_candidate =
      !candidate_ ||
      (result.T_world_camera.translation() - candidate_->odom_position).norm() >= confirm_distance_;
  bool due = false;
  if (has_pose_) {  // every n-th frame with a pose
    if (mode_ == SlamMode::kLocalization) {
      due = map_has_keyframes &&
            (localized_ ? result.keyframe.has_value() : frames_since_attempt_++ % every_ == 0);
    } else if (recovering_ && !far_from_candidate) {
      due = false;
    } else {
      due = recovering_ && frames_since_attempt_++ % every_ == 0;
    }
  }
  const bool from_user = user_request_.has_value();
  if (!due && !from_user) return decision;
  if (!has_pose_) {
    decision.failure =
        result.map_kept
            ? "this frame could not be tracked (the tracker searches the next ones in its map)"
            : "tracking is lost and the frame has too few stereo points";
    decision.from_user = from_user;
    return decision;
  }
  const bool recover = mode_ == SlamMode::kMapping && recovering_;
  decision.ask = true;
  decision.from_user = from_user;
  decision.scope =
      recover ? RelocalizationRequest::Scope::kMap : RelocalizationRequest::Scope::kAnywhere;
  // Mapping: after a loss the edge is what joins the odometry to the map; while tracking is
  // fine it corrects map -> odom only when the user asks to re-anchor. Localization never
  // changes the map: the result moves map -> odom instead.
  // A recovery's first success is only a candidate: no edge until one from elsewhere agrees.
  // While recovering, a user's request follows the same rule (re-anchoring or not: one view
  // proves nothing in a building of look-alikes); one from near the candidate is a check only.
  const bool confirming = recover && candidate_.has_value() && far_from_candidate;
  decision.add_edge =
      mode_ == SlamMode::kMapping &&
      (recover ? confirm_distance_ == 0 || confirming : from_user && user_request_->reanchor);
  if (confirming) decision.expected_T_map_camera = candidate_->T_map_odom * result.T_world_camera;
  return decision;
}

RelocalizationOutcome RelocalizationPolicy::OnAnswer(const RelocalizationRequest& request,
                                                     const RelocalizationAnswer& answer) {
  RelocalizationOutcome outcome;
  const relocalization::Relocalization& found = answer.result;
  if (mode_ == SlamMode::kLocalization) {
    if (found.success() && answer.map_pose_known) {
      T_map_odom_ = answer.T_map_camera * request.T_odom_camera.inverse();
      outcome.T_map_odom = T_map_odom_;
      if (!localized_) outcome.news = "localized in the map against " + FoundText(found);
      localized_ = true;
      frames_since_attempt_ = 0;
    }
  } else if (recovering_ && (found.success() || answer.already_joined)) {
    // Joined: by a loop meanwhile, by this answer's edge (a confirmation, or the user's
    // re-anchoring), or by a success that needs no confirmation or agrees with the candidate.
    const bool joined = answer.already_joined || answer.edge.has_value() ||
                        confirm_distance_ == 0 || answer.agrees.value_or(false);
    if (joined) {
      recovering_ = false;
      if (found.success()) {
        outcome.news = "found in the map again after " + break_reason_ + " against " +
                       FoundText(found) +
                       (candidate_ ? ", as the candidate against keyframe " +
                                         std::to_string(candidate_->keyframe_id) + " had it"
                                   : std::string()) +
                       "; its segment is joined to the map";
      }
      break_reason_ = "tracking loss";
      candidate_.reset();
    } else if (answer.map_pose_known && (!candidate_ || request.expected_T_map_camera)) {
      // The first candidate, or a view from elsewhere that disagrees with it: the newer view is
      // the candidate. (A user's check from near the candidate leaves it as it is.)
      if (candidate_) {
        outcome.news = "relocalized against " + FoundText(found) +
                       ", which disagrees with the candidate against keyframe " +
                       std::to_string(candidate_->keyframe_id) + ": the new candidate";
      }
      candidate_ = Candidate{answer.T_map_camera * request.T_odom_camera.inverse(),
                             request.T_odom_camera.translation(), found.keyframe_id};
    }
  }
  if (request.from_user) {
    UserRelocalization user;
    user.success = found.success() && answer.map_pose_known;
    if (answer.already_joined) {
      user.message = "the camera's segment was joined to the map by a loop meanwhile; ask again";
    } else if (found.success() && !answer.map_pose_known) {
      user.message = "found against keyframe " + std::to_string(found.keyframe_id) +
                     ", which the map graph does not hold yet";
    } else {
      user.message =
          std::string(relocalization::RelocalizationStatusName(found.status)) + ": " + found.reason;
    }
    user.inliers = found.inliers;
    user.probability = found.probability;
    user.time_ms = answer.ms;
    if (found.success()) user.keyframe_id = found.keyframe_id;
    user.T_map_camera = answer.T_map_camera;
    outcome.user = user;
    user_request_.reset();
  }
  return outcome;
}

UserRelocalization RelocalizationPolicy::FailUserRequest(const std::string& failure) {
  user_request_.reset();
  UserRelocalization user;
  user.message = failure;
  return user;
}

RelocalizationOutcome RelocalizationPolicy::OnNoAnswer(const RelocalizationRequest& request,
                                                       const std::string& reason) {
  RelocalizationOutcome outcome;
  if (request.from_user) outcome.user = FailUserRequest(reason);
  return outcome;
}

bool RelocalizationPolicy::on_map() const {
  if (mode_ == SlamMode::kLocalization) return localized_ && has_pose_;
  return reference_keyframe_ >= 0 && !recovering_;
}

std::optional<Eigen::Isometry3d> RelocalizationPolicy::T_map_camera() const {
  if (mode_ != SlamMode::kLocalization || !on_map()) return std::nullopt;
  return T_map_odom_ * T_odom_camera_;
}

}  // namespace stereo_fabmap_slam::pipeline
