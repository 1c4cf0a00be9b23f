#include "stereo_fabmap_slam/odometry/tracker.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <stdexcept>

#include "stereo_fabmap_slam/features/descriptor_matching.h"
#include "stereo_fabmap_slam/features/feature_factory.h"
#include "stereo_fabmap_slam/features/keypoint_grid.h"
#include "stereo_fabmap_slam/geometry/image_coverage.h"

namespace stereo_fabmap_slam::odometry {
namespace {

constexpr double kRadiansToDegrees = 180.0 / M_PI;

double RotationDegrees(const Eigen::Isometry3d& motion) {
  return Eigen::AngleAxisd(motion.linear()).angle() * kRadiansToDegrees;
}

// `factor` times the motion: its rotation angle (about the same axis) and translation scaled.
Eigen::Isometry3d ScaleMotion(const Eigen::Isometry3d& motion, double factor) {
  const Eigen::AngleAxisd rotation(motion.linear());
  Eigen::Isometry3d scaled = Eigen::Isometry3d::Identity();
  scaled.linear() =
      Eigen::AngleAxisd(factor * rotation.angle(), rotation.axis()).toRotationMatrix();
  scaled.translation() = factor * motion.translation();
  return scaled;
}

}  // namespace

const char* TrackingStateName(TrackingState state) {
  switch (state) {
    case TrackingState::kOk:
      return "ok";
    case TrackingState::kWeak:
      return "weak";
    case TrackingState::kLost:
      return "lost";
  }
  return "?";
}

Tracker::Tracker(const TrackerOptions& options, const KeyframePolicyOptions& keyframe_options,
                 const geometry::StereoCamera& camera, int descriptor_norm,
                 double max_descriptor_distance, concurrency::HelperThread* helper)
    : options_((options.Validate(), options)),
      keyframe_policy_(keyframe_options),
      camera_(camera),
      descriptor_norm_(descriptor_norm),
      max_descriptor_distance_(max_descriptor_distance),
      helper_(options.parallel ? helper : nullptr),
      local_map_(options.local_keyframes) {
  ransac_options_.kernel = options.pnp_kernel;
  ransac_options_.reprojection_threshold = options.ransac_threshold;
  ransac_options_.max_iterations = options.ransac_iterations;
  // Matches by descriptor alone have a lower inlier ratio than those found by projection (down
  // to a third, where repeated texture gives look-alikes): 100 AP3P samples then find an
  // all-inlier triple with 93 % probability, 500 with 99.9999 %. OpenCV stops early once the
  // consensus is large, so the cost is paid only when the matches are poor.
  ransac_options_without_prior_ = ransac_options_;
  ransac_options_without_prior_.max_iterations = 5 * options.ransac_iterations;
}

void Tracker::Reset() {
  local_map_.Clear();
  has_last_ = false;
  velocity_ = Eigen::Isometry3d::Identity();
  velocity_dt_ = 0;
  frames_since_tracked_ = 0;
  recent_frames_skipped_.fill(0);
}

std::vector<Tracker::Match> Tracker::SearchByProjection(const features::StereoFeatures& features,
                                                        const Eigen::Isometry3d& T_camera_world,
                                                        double radius) const {
  const features::KeypointGrid grid(features.keypoints, camera_.size, 16);
  std::vector<const MapPoint*> points;
  points.reserve(local_map_.points().size());
  for (const auto& entry : local_map_.points()) points.push_back(&entry.second);  // id order

  // Best map point for each key point (none while `point` is null); ties go to the lower point
  // id, so that the result does not depend on how the points are split between threads. A
  // vector by key point, not a hash map: no allocation per match (a long run's fragmented heap
  // makes many small allocations slower and slower, docs/benchmarks.md), and key point order
  // for free.
  using BestByKeypoint = std::vector<Match>;
  const auto keep_better = [](BestByKeypoint* best, const Match& m) {
    Match& current = (*best)[static_cast<std::size_t>(m.keypoint)];
    if (current.point == nullptr || m.distance < current.distance ||
        (m.distance == current.distance && m.point->id < current.point->id)) {
      current = m;
    }
  };
  const auto search = [&](std::size_t begin, std::size_t end, BestByKeypoint* best_by_keypoint) {
    for (std::size_t k = begin; k < end; ++k) {
      const MapPoint* point = points[k];
      const Eigen::Vector3d c = T_camera_world * point->position;
      if (c.z() < 0.05) continue;
      const double u = camera_.fx * c.x() / c.z() + camera_.cx;
      const double v = camera_.fy * c.y() / c.z() + camera_.cy;
      if (u < 0 || v < 0 || u >= camera_.size.width || v >= camera_.size.height) continue;
      double best = std::numeric_limits<double>::max(), second = best;
      int best_index = -1;
      grid.ForEachWithin(u, v, radius, [&](int i) {
        const double distance = features::DescriptorDistance(
            point->descriptor, 0, features.descriptors, i, descriptor_norm_);
        if (distance < best) {
          second = best;
          best = distance;
          best_index = i;
        } else if (distance < second) {
          second = distance;
        }
      });
      if (best_index < 0 || best > max_descriptor_distance_ ||
          best > options_.match_ratio * second) {
        continue;
      }
      keep_better(best_by_keypoint, Match{point, best_index, best});
    }
  };

  const Match none{nullptr, -1, 0.0};
  BestByKeypoint best_by_keypoint(features.keypoints.size(), none);
  if (helper_ != nullptr) {
    // Four pieces of the points, each with its own best per key point, merged in piece order
    // (keep_better's tie rule makes the order irrelevant anyway).
    constexpr int kPieces = 4;
    std::vector<BestByKeypoint> pieces(kPieces, BestByKeypoint(features.keypoints.size(), none));
    helper_->ForEachPiece(kPieces, [&](int piece) {
      search(points.size() * piece / kPieces, points.size() * (piece + 1) / kPieces,
             &pieces[static_cast<std::size_t>(piece)]);
    });
    for (const BestByKeypoint& piece : pieces) {
      for (const Match& m : piece) {
        if (m.point != nullptr) keep_better(&best_by_keypoint, m);
      }
    }
  } else {
    search(0, points.size(), &best_by_keypoint);
  }
  std::vector<Match> matches;
  for (const Match& m : best_by_keypoint) {
    if (m.point != nullptr) matches.push_back(m);
  }
  return matches;
}

std::vector<Tracker::Match> Tracker::SearchByDescriptor(
    const features::StereoFeatures& features) const {
  std::vector<const MapPoint*> points;
  std::vector<cv::Mat> rows;
  // The whole local map, not only the last keyframe's points: on MH01 at every 3rd and 4th
  // pair the last keyframe alone lost a frame and gave 3.1 cm of odometry ATE where the local
  // map kept every frame at 0.5-0.8 cm, for 12-19 ms a search instead of 22-30 ms (RANSAC
  // included). The search runs only when the prediction failed.
  points.reserve(local_map_.points().size());
  rows.reserve(local_map_.points().size());
  for (const auto& entry : local_map_.points()) {
    points.push_back(&entry.second);
    rows.push_back(entry.second.descriptor);  // a header: the copy is vconcat's, once
  }
  cv::Mat descriptors;
  if (!rows.empty()) cv::vconcat(rows, descriptors);
  std::vector<Match> matches;
  for (const cv::DMatch& m :
       features::RatioTestMatches(features.descriptors, descriptors, descriptor_norm_,
                                  max_descriptor_distance_, options_.match_ratio)) {
    matches.push_back(Match{points[static_cast<std::size_t>(m.trainIdx)], m.queryIdx,
                            static_cast<double>(m.distance)});
  }
  return matches;
}

geometry::PnpResult Tracker::SolvePose(const features::StereoFeatures& features,
                                       const std::vector<Match>& matches,
                                       const geometry::PnpRansacOptions& ransac_options,
                                       const Eigen::Isometry3d& guess) const {
  std::vector<geometry::PnpCorrespondence> correspondences;
  correspondences.reserve(matches.size());
  for (const Match& m : matches) {
    const auto i = static_cast<std::size_t>(m.keypoint);
    const cv::Point2f& pixel = features.keypoints[i].pt;
    correspondences.push_back(
        {m.point->position, {pixel.x, pixel.y}, features.HasDepth(i), features.points[i]});
  }
  return geometry::SolvePnpRansac(correspondences, camera_, ransac_options, guess);
}

std::vector<geometry::PoseObservation> Tracker::Observations(
    const features::StereoFeatures& features, const std::vector<Match>& matches) const {
  std::vector<geometry::PoseObservation> observations;
  observations.reserve(matches.size());
  for (const Match& m : matches) {
    const cv::Point2f& p = features.keypoints[m.keypoint].pt;
    observations.push_back({m.point->position, p.x, p.y, features.u_right[m.keypoint]});
  }
  return observations;
}

map::Keyframe Tracker::MakeKeyframe(double timestamp, features::StereoFeatures features,
                                    const Eigen::Isometry3d& T_world_camera,
                                    const std::vector<Match>& inlier_matches,
                                    bool starts_new_segment) {
  map::Keyframe keyframe;
  keyframe.id = next_keyframe_id_++;
  keyframe.timestamp = timestamp;
  keyframe.T_world_camera = T_world_camera;
  keyframe.starts_new_segment = starts_new_segment;
  keyframe.map_point_ids.assign(features.size(), -1);
  const std::int64_t keyframe_point_ids_begin = next_point_id_;
  for (const Match& m : inlier_matches) keyframe.map_point_ids[m.keypoint] = m.point->id;
  for (std::size_t i = 0; i < features.size(); ++i) {
    if (keyframe.map_point_ids[i] < 0 && features.HasDepth(i)) {
      keyframe.map_point_ids[i] = next_point_id_++;
    }
  }
  keyframe.features = std::move(features);
  local_map_.AddKeyframe(keyframe);
  last_keyframe_pose_ = T_world_camera;
  last_keyframe_time_ = timestamp;
  first_point_of_last_keyframe_ = keyframe_point_ids_begin;
  most_settled_since_keyframe_ = static_cast<int>(inlier_matches.size());
  last_settled_points_ = most_settled_since_keyframe_;
  return keyframe;
}

void Tracker::StartMap(double timestamp, features::StereoFeatures features,
                       const Eigen::Isometry3d& T_world_camera, TrackingResult* result) {
  result->T_world_camera = T_world_camera;
  if (features.CountWithDepth() < options_.min_map_points) {
    result->reason += (result->reason.empty() ? "" : "; ") +
                      std::string("too few stereo points (") +
                      std::to_string(features.CountWithDepth()) + ") to start a map";
    return;
  }
  const bool starts_new_segment = had_map_;
  local_map_.Clear();
  result->keyframe =
      MakeKeyframe(timestamp, std::move(features), T_world_camera, {}, starts_new_segment);
  had_map_ = true;
  result->reason += (result->reason.empty() ? "" : "; ") + std::string("map started");
}

void Tracker::Remember(double timestamp, const Eigen::Isometry3d& T_world_camera,
                       TrackingResult* result) {
  if (has_last_) {
    velocity_ = last_T_world_camera_.inverse() * T_world_camera;
    velocity_dt_ = timestamp - last_timestamp_;
  }
  last_timestamp_ = timestamp;
  frames_since_tracked_ = 0;
  has_last_ = true;
  last_T_world_camera_ = T_world_camera;
  result->T_world_camera = T_world_camera;
  if (!local_map_.empty()) {
    result->reference_keyframe = local_map_.last_keyframe_id();
    result->T_keyframe_camera = last_keyframe_pose_.inverse() * T_world_camera;
  }
}

namespace {

// Fills the result's key point classes; `inlier[k]` says whether matched key point
// `matched[k]` was an inlier.
void ClassifyKeypoints(const features::StereoFeatures& features, const std::vector<int>& matched,
                       const std::vector<bool>& inlier, TrackingResult* result) {
  std::vector<bool> is_matched(features.size(), false);
  for (std::size_t k = 0; k < matched.size(); ++k) {
    const std::size_t i = static_cast<std::size_t>(matched[k]);
    is_matched[i] = true;
    (inlier[k] ? result->inlier_pixels : result->outlier_pixels)
        .push_back(features.keypoints[i].pt);
  }
  for (std::size_t i = 0; i < features.size(); ++i) {
    if (!is_matched[i] && features.HasDepth(i)) {
      result->untracked_pixels.push_back(features.keypoints[i].pt);
    }
  }
}

// The pose is the motion model's guess (or the origin), not an estimate: its covariance is
// unknown, and no key point was tracked, whatever a failed attempt classified.
void MarkUntracked(const features::StereoFeatures& features, TrackingResult* result) {
  constexpr double kUnknownVariance = 1e6;
  result->covariance = geometry::PoseCovariance::Identity() * kUnknownVariance;
  result->inlier_pixels.clear();
  result->outlier_pixels.clear();
  result->untracked_pixels.clear();
  ClassifyKeypoints(features, {}, {}, result);
}

}  // namespace

TrackingResult Tracker::Lose(double timestamp, features::StereoFeatures features,
                             const Eigen::Isometry3d& predicted, int consensus,
                             TrackingResult result) {
  // The map is kept only for a frame that still sees it, if too poorly to trust a pose (motion
  // blur, a close-up of few points): a consensus beyond a minimal sample (4 points for P3P and
  // its check). Matches that are wrong agree with a pose within the RANSAC threshold by chance
  // with odds of about 1e-4 each (a 2 px disc in a 752 x 480 image), so two beyond the sample
  // are evidence. A camera that sees nothing of the local map (kidnapped, or facing a wall)
  // starts a new segment at once, which relocalization joins to the map.
  constexpr int kConsensusThatSeesTheMap = 6;
  const double since_tracked = timestamp - last_timestamp_;
  if (since_tracked > options_.max_time_lost || consensus < kConsensusThatSeesTheMap) {
    return StartOver(timestamp, std::move(features), predicted, std::move(result));
  }
  // Nothing is remembered: the next frame is predicted from the last tracked one, over the
  // whole gap, and the time without tracking keeps counting from there.
  MarkUntracked(features, &result);
  result.T_world_camera = predicted;
  result.map_kept = true;
  char kept[96];
  std::snprintf(kept, sizeof(kept),
                "; map kept (%.2f s since the last tracked frame, at most %.2f)", since_tracked,
                options_.max_time_lost);
  result.reason += kept;
  return result;
}

TrackingResult Tracker::StartOver(double timestamp, features::StereoFeatures features,
                                  const Eigen::Isometry3d& predicted, TrackingResult result) {
  MarkUntracked(features, &result);
  StartMap(timestamp, std::move(features), predicted, &result);
  if (!result.keyframe) result.state = TrackingState::kLost;
  Remember(timestamp, predicted, &result);
  return result;
}

Eigen::Isometry3d Tracker::Predict(double timestamp) const {
  if (!has_last_) return start_pose_;
  // The motion over the time to this frame: when frames were skipped (a busy tracker, a bag
  // played faster than real time) or come faster, the last motion is scaled by the ratio of the
  // gaps. Gaps within a third of each other count as the same: camera clocks jitter, and a
  // scaled prediction would only add that jitter to the motion.
  const double dt = timestamp - last_timestamp_;
  if (dt > options_.max_prediction_gap) return last_T_world_camera_;
  const double ratio = velocity_dt_ > 0 && dt > 0 ? dt / velocity_dt_ : 1.0;
  if (ratio < 1.5 && ratio > 1 / 1.5) return last_T_world_camera_ * velocity_;
  return last_T_world_camera_ * ScaleMotion(velocity_, ratio);
}

TrackingResult Tracker::Track(double timestamp, features::StereoFeatures features,
                              int frames_skipped) {
  frames_since_tracked_ += std::max(frames_skipped, 0) + 1;
  recent_frames_skipped_[next_skip_slot_] = std::max(frames_skipped, 0);
  next_skip_slot_ = (next_skip_slot_ + 1) % kSkipHistory;
  TrackingResult result;
  const Eigen::Isometry3d predicted = Predict(timestamp);

  if (local_map_.empty()) {
    result.state = TrackingState::kOk;
    return StartOver(timestamp, std::move(features), predicted, std::move(result));
  }

  // Coarse search around the predicted pose (wider if that finds too little), RANSAC, refine.
  std::vector<Match> matches =
      SearchByProjection(features, predicted.inverse(), options_.search_radius);
  if (static_cast<int>(matches.size()) < options_.min_inliers_ok) {
    matches = SearchByProjection(features, predicted.inverse(), 3.0 * options_.search_radius);
  }
  geometry::PnpResult ransac = SolvePose(features, matches, ransac_options_, predicted.inverse());
  result.matches = static_cast<int>(matches.size());
  const auto inliers = [](const geometry::PnpResult& r) {
    return r.success ? static_cast<int>(r.inliers.size()) : 0;
  };
  const bool searched_by_descriptor = inliers(ransac) < options_.min_inliers_ok;
  const int prediction_consensus = inliers(ransac);
  bool found_by_descriptor = false;
  if (searched_by_descriptor) {
    // The prediction found too little: the camera moved other than the motion model says (it
    // turned or stopped over frames a busy tracker skipped, or right after a new segment started
    // with an old velocity). Descriptors alone find the frame in the local map wherever it is;
    // the better of the two consensus sets wins, so a weak but right prediction is kept.
    const std::vector<Match> by_descriptor = SearchByDescriptor(features);
    geometry::PnpResult without_prior =
        SolvePose(features, by_descriptor, ransac_options_without_prior_, predicted.inverse());
    if (inliers(without_prior) > inliers(ransac)) {
      result.reason = "found by descriptor (" + std::to_string(inliers(without_prior)) +
                      " RANSAC inliers of " + std::to_string(by_descriptor.size()) +
                      " matches; the prediction gave " + std::to_string(inliers(ransac)) + ")";
      ransac = std::move(without_prior);
      result.matches = static_cast<int>(by_descriptor.size());
      found_by_descriptor = true;
    }
  }
  if (inliers(ransac) < options_.min_inliers_weak) {
    result.state = TrackingState::kLost;
    result.reason = "only " + std::to_string(inliers(ransac)) + " RANSAC inliers of " +
                    std::to_string(result.matches) + " matches" +
                    (searched_by_descriptor ? ", by projection or by descriptor" : "");
    return Lose(timestamp, std::move(features), predicted, inliers(ransac), std::move(result));
  }
  // The RANSAC pose is already re-fitted to its whole consensus set (by OpenCV, or by the
  // Umeyama kernel): good enough to search again with a fine radius, which finds the points
  // the coarse search missed, before the robust refinement.
  matches = SearchByProjection(features, ransac.T_camera_world, options_.search_radius_fine);
  std::vector<geometry::PoseObservation> observations = Observations(features, matches);
  const geometry::PoseRefinement refined =
      geometry::RefinePose(observations, camera_, ransac.T_camera_world, options_.refinement);
  std::vector<Match> inlier_matches;
  std::vector<int> matched_keypoints;
  for (std::size_t k = 0; k < matches.size(); ++k) {
    if (refined.inlier[k]) inlier_matches.push_back(matches[k]);
    matched_keypoints.push_back(matches[k].keypoint);
  }
  ClassifyKeypoints(features, matched_keypoints, refined.inlier, &result);
  result.matches = static_cast<int>(matches.size());
  result.inliers = refined.inliers;
  result.covariance = refined.covariance;
  const Eigen::Isometry3d T_world_camera = refined.T_camera_world.inverse();

  if (result.inliers < options_.min_inliers_weak) {
    result.state = TrackingState::kLost;
    result.reason += (result.reason.empty() ? "" : "; ") + std::string("only ") +
                     std::to_string(result.inliers) + " inliers after refinement";
    return Lose(timestamp, std::move(features), predicted, inliers(ransac), std::move(result));
  }
  if (found_by_descriptor) {
    const Eigen::Isometry3d jump = predicted.inverse() * T_world_camera;
    char text[64];
    std::snprintf(text, sizeof(text), "; %.2f m, %.0f deg from the prediction",
                  jump.translation().norm(), RotationDegrees(jump));
    result.reason += text;
    if (!EnoughToJump(jump, result)) {
      result.state = TrackingState::kLost;
      result.reason += ": too far for " + std::to_string(result.inliers) + " inliers";
      // The map is kept only if the prediction itself still saw it.
      return Lose(timestamp, std::move(features), predicted, prediction_consensus,
                  std::move(result));
    }
  }
  result.state =
      result.inliers < options_.min_inliers_ok ? TrackingState::kWeak : TrackingState::kOk;
  if (result.state == TrackingState::kWeak) {
    result.reason +=
        (result.reason.empty() ? "" : "; ") + std::to_string(result.inliers) + " inliers";
  }

  const int settled_points = static_cast<int>(std::count_if(
      inlier_matches.begin(), inlier_matches.end(),
      [this](const Match& m) { return m.point->id < first_point_of_last_keyframe_; }));
  const KeyframeDecision decision =
      keyframe_policy_.Decide(KeyframeInput(timestamp, T_world_camera, result, settled_points));
  if (decision.insert) {
    result.keyframe =
        MakeKeyframe(timestamp, std::move(features), T_world_camera, inlier_matches, false);
    result.reason += (result.reason.empty() ? "" : "; ") + ("keyframe: " + decision.reason);
  } else {
    last_settled_points_ = settled_points;
  }
  Remember(timestamp, T_world_camera, &result);
  return result;
}

bool Tracker::EnoughToJump(const Eigen::Isometry3d& jump, const TrackingResult& result) const {
  if (jump.translation().norm() <= options_.max_descriptor_jump &&
      RotationDegrees(jump) <= options_.max_descriptor_jump_deg) {
    return true;
  }
  std::vector<Eigen::Vector2d> pixels;
  for (const cv::Point2f& pixel : result.inlier_pixels) pixels.emplace_back(pixel.x, pixel.y);
  return result.inliers >= options_.min_inliers_ok &&
         geometry::OccupiedCells(pixels, camera_.size, geometry::kInlierSpreadGrid) >=
             options_.jump_min_inlier_cells;
}

KeyframePolicyInput Tracker::KeyframeInput(double timestamp,
                                           const Eigen::Isometry3d& T_world_camera,
                                           const TrackingResult& result, int settled_points) {
  KeyframePolicyInput input;
  input.tracked_points = result.inliers;
  input.tracking_weak = result.state == TrackingState::kWeak;
  // The settled points tracked rise in the frames after a keyframe (points it inherited but did
  // not match come back into view) and then fall as the camera moves on: compare with the peak.
  most_settled_since_keyframe_ = std::max(most_settled_since_keyframe_, settled_points);
  input.reference_settled_points = most_settled_since_keyframe_;
  const Eigen::Isometry3d since_keyframe = last_keyframe_pose_.inverse() * T_world_camera;
  input.now.settled_points = settled_points;
  input.now.translation = since_keyframe.translation().norm();
  input.now.rotation_deg = RotationDegrees(since_keyframe);
  input.now.time = timestamp - last_keyframe_time_;

  const double gap = timestamp - last_timestamp_;
  const int frames_to_skip =
      *std::max_element(recent_frames_skipped_.begin(), recent_frames_skipped_.end());
  if (frames_to_skip > 0 && has_last_ && gap > 0) {
    // The caller will likely skip `frames_to_skip` frames before the next one
    // (recent_frames_skipped_): the last of those lies that many camera frames ahead, of the
    // frames_since_tracked_ the gap since the last tracked frame spans (frames lost with the map
    // kept are in the gap too). Motion and the loss of settled points go on as over that gap.
    const double ahead = static_cast<double>(frames_to_skip) / frames_since_tracked_;
    const Eigen::Isometry3d last_step = last_T_world_camera_.inverse() * T_world_camera;
    const Eigen::Isometry3d then = since_keyframe * ScaleMotion(last_step, ahead);
    KeyframeMeasures& measures = input.before_next_frame.emplace();
    measures.settled_points = static_cast<int>(
        std::lround(settled_points + ahead * (settled_points - last_settled_points_)));
    measures.translation = then.translation().norm();
    measures.rotation_deg = RotationDegrees(then);
    measures.time = input.now.time + ahead * gap;
  }
  return input;
}

void Tracker::ApplyUpdate(const map::KeyframeUpdate& update) {
  if (local_map_.empty()) return;
  const std::int64_t last_id = local_map_.last_keyframe_id();
  local_map_.ApplyUpdate(update);
  // Keep the last frame where it is relative to the last keyframe, so that the motion model and
  // the next prediction live in the corrected map.
  if (const Eigen::Isometry3d* corrected = local_map_.KeyframePose(last_id)) {
    const Eigen::Isometry3d relative = last_keyframe_pose_.inverse() * last_T_world_camera_;
    last_keyframe_pose_ = *corrected;
    last_T_world_camera_ = *corrected * relative;
  }
}

}  // namespace stereo_fabmap_slam::odometry
