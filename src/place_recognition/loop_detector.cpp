#include "stereo_fabmap_slam/place_recognition/loop_detector.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <numeric>
#include <stdexcept>

#include "stereo_fabmap_slam/geometry/relative_pose_error.h"
#include "stereo_fabmap_slam/place_recognition/place_database.h"

namespace stereo_fabmap_slam::place_recognition {
namespace {

constexpr double kDegreesToRadians = M_PI / 180.0;

double RotationDegrees(const Eigen::Matrix3d& rotation) {
  return Eigen::AngleAxisd(rotation).angle() / kDegreesToRadians;
}

}  // namespace

LoopDetector::LoopDetector(const LoopDetectorOptions& options, Vocabulary vocabulary, FabMap fabmap,
                           const geometry::StereoCamera& camera, int descriptor_norm,
                           double max_descriptor_distance)
    : options_((options.Validate(), options)),
      vocabulary_(std::move(vocabulary)),
      fabmap_(std::move(fabmap)),
      verifier_(camera, descriptor_norm, max_descriptor_distance),
      vocabulary_fingerprint_(vocabulary_.Fingerprint()),
      sequence_({options_.sequence_length, options_.sequence_max_step}) {
  if (fabmap_.model().size() != vocabulary_.size()) {
    throw std::invalid_argument("the Chow-Liu tree has " + std::to_string(fabmap_.model().size()) +
                                " words, the vocabulary " + std::to_string(vocabulary_.size()) +
                                ": they were not trained together");
  }
}

std::vector<int> LoopDetector::Words(const map::Keyframe& keyframe) const {
  try {
    return Words(keyframe.place_descriptors);
  } catch (const std::invalid_argument& error) {
    throw std::invalid_argument("keyframe " + std::to_string(keyframe.id) + ": " + error.what());
  }
}

std::vector<int> LoopDetector::Words(const cv::Mat& descriptors) const {
  if (descriptors.empty()) return {};
  const bool binary = descriptors.type() == CV_8U;
  const int bytes = static_cast<int>(descriptors.cols * descriptors.elemSize());
  if ((descriptors.type() != CV_8U && descriptors.type() != CV_32F) ||
      binary != vocabulary_.binary() || bytes != vocabulary_.descriptor_bytes()) {
    throw std::invalid_argument(
        std::string("place descriptors are ") + (binary ? "binary" : "float") + " of " +
        std::to_string(bytes) + " bytes, the vocabulary's " +
        (vocabulary_.binary() ? "binary" : "float") + " of " +
        std::to_string(vocabulary_.descriptor_bytes()) +
        " bytes: train a vocabulary with the odometry's descriptor (train_fabmap)");
  }
  return vocabulary_.WordSet(descriptors);
}

const map::StoredKeyframe& LoopDetector::Add(map::Keyframe keyframe) {
  std::vector<int> words = Words(keyframe);
  return Add(std::move(keyframe), std::move(words));
}

const map::StoredKeyframe& LoopDetector::Add(map::Keyframe keyframe, std::vector<int> words) {
  for (const int word : words) {
    if (word < 0 || word >= vocabulary_.size()) {
      throw std::invalid_argument("keyframe " + std::to_string(keyframe.id) + " has word " +
                                  std::to_string(word) + " outside the vocabulary");
    }
  }
  const map::StoredKeyframe& stored = database_.Add(std::move(keyframe), std::move(words));
  AddPlace(stored);
  return stored;
}

LoopDetector LoopDetector::WithoutKeyframes() const {
  FabMap fabmap = fabmap_;
  fabmap.SetPlaces(PlaceDatabase(vocabulary_.size()));
  return LoopDetector(options_, vocabulary_, std::move(fabmap), verifier_.camera(),
                      verifier_.descriptor_norm(), verifier_.max_descriptor_distance());
}

LoopDetection LoopDetector::Process(map::Keyframe keyframe, bool add_to_map) {
  if (add_to_map) return Detect(Add(std::move(keyframe)));
  // Compared without being stored: it has no place on the odometry path to check against.
  map::StoredKeyframe query;
  query.words = Words(keyframe);
  query.keyframe = std::move(keyframe);
  query.segment = -1;  // unknown: no odometry prediction to check against
  return Detect(query);
}

LoopDetection LoopDetector::DetectStored(std::int64_t keyframe_id) {
  const map::StoredKeyframe& stored = database_.Get(keyframe_id);
  return Detect(stored);
}

void LoopDetector::AddPlace(const map::StoredKeyframe& stored) {
  fabmap_.AddPlace(stored.words);
  place_keyframes_.push_back(stored.keyframe.id);
}

std::vector<char> LoopDetector::AllowedPlaces(
    const std::function<bool(const map::StoredKeyframe&)>& allowed) const {
  std::vector<char> mask(place_keyframes_.size(), 0);
  for (std::size_t i = 0; i < place_keyframes_.size(); ++i) {
    mask[i] = allowed(database_.Get(place_keyframes_[i])) ? 1 : 0;
  }
  return mask;
}

PlaceQuery LoopDetector::Ranked(const FabMapResult& result, const std::vector<char>& mask,
                                const std::vector<double>& score,
                                const std::function<bool(std::size_t)>& eligible,
                                int max_candidates) const {
  PlaceQuery query;
  query.new_place_probability = result.new_place;
  query.places_compared = static_cast<int>(std::count(mask.begin(), mask.end(), 1));
  std::vector<int> order;
  for (std::size_t i = 0; i < mask.size(); ++i) {
    if (mask[i] && eligible(i)) order.push_back(static_cast<int>(i));
  }
  std::sort(order.begin(), order.end(),
            [&](int a, int b) { return score[a] > score[b] || (score[a] == score[b] && a < b); });
  if (static_cast<int>(order.size()) > max_candidates) order.resize(max_candidates);
  for (const int place : order) {
    query.candidates.push_back({place_keyframes_[place], result.posterior[place]});
  }
  return query;
}

PlaceQuery LoopDetector::Candidates(const std::vector<int>& words,
                                    const std::function<bool(const map::StoredKeyframe&)>& allowed,
                                    int max_candidates, double min_probability,
                                    double min_log_odds) const {
  const std::vector<char> mask = AllowedPlaces(allowed);
  if (std::count(mask.begin(), mask.end(), 1) == 0 || words.empty()) {
    PlaceQuery query;
    query.places_compared = static_cast<int>(std::count(mask.begin(), mask.end(), 1));
    return query;
  }
  const FabMapResult result = fabmap_.Compare(words, mask);
  // Best posterior first, which is the order of the log odds too.
  return Ranked(
      result, mask, result.posterior,
      [&](std::size_t i) {
        return result.posterior[i] >= min_probability &&
               result.CandidateLogOdds(static_cast<int>(i)) >= min_log_odds;
      },
      max_candidates);
}

FabMapResult LoopDetector::CompareAllowed(const std::vector<int>& words,
                                          const std::vector<char>& mask,
                                          std::vector<double>* log_odds) const {
  log_odds->assign(mask.size(), -std::numeric_limits<double>::infinity());
  FabMapResult result;
  result.posterior.assign(mask.size(), 0.0);
  if (std::count(mask.begin(), mask.end(), 1) == 0 || words.empty()) return result;
  result = fabmap_.Compare(words, mask);
  for (std::size_t i = 0; i < mask.size(); ++i) {
    if (mask[i]) (*log_odds)[i] = result.CandidateLogOdds(static_cast<int>(i));
  }
  return result;
}

PlaceQuery LoopDetector::SequenceCandidates(
    const std::vector<int>& words, const std::function<bool(const map::StoredKeyframe&)>& allowed,
    std::int64_t segment, int max_candidates) const {
  const bool chained = options_.sequence_length > 1 && segment >= 0 && segment == sequence_segment_;
  if (!chained) return Candidates(words, allowed, max_candidates, 0.0);
  const std::vector<char> mask = AllowedPlaces(allowed);
  std::vector<double> log_odds;
  const FabMapResult result = CompareAllowed(words, mask, &log_odds);
  const std::vector<double> scores = sequence_.Peek(log_odds);
  return Ranked(
      result, mask, scores, [&](std::size_t i) { return std::isfinite(scores[i]); },
      max_candidates);
}

LoopDetection LoopDetector::Detect(const map::StoredKeyframe& query) {
  const double query_time = query.keyframe.timestamp;
  LoopDetection detection;
  detection.query_id = query.keyframe.id;
  // Keyframes within min_age of the query (either way: a stored query sees newer ones too) are
  // no places to return to; the posterior is taken over the others only.
  const auto old_enough = [&](const map::StoredKeyframe& place) {
    return place.keyframe.id != query.keyframe.id &&
           std::abs(place.keyframe.timestamp - query_time) >= options_.min_age;
  };
  PlaceQuery places;
  // A stored keyframe queried for the first time extends the sequence of its segment; without a
  // sequence (off, a view that is not stored, a repeated query) one view ranks alone.
  const bool extends_sequence =
      options_.sequence_length > 1 && query.segment >= 0 && query.keyframe.id > sequence_last_id_;
  if (!extends_sequence) {
    places = Candidates(query.words, old_enough, options_.max_candidates, options_.min_probability,
                        options_.min_log_odds);
  } else {
    const std::vector<char> mask = AllowedPlaces(old_enough);
    std::vector<double> log_odds;
    const FabMapResult result = CompareAllowed(query.words, mask, &log_odds);
    if (query.segment != sequence_segment_) sequence_.Reset();
    sequence_segment_ = query.segment;
    sequence_last_id_ = query.keyframe.id;
    const std::vector<double> scores = sequence_.Push(log_odds);
    places = Ranked(
        result, mask, scores,
        // Allowed places have finite log odds, so finite scores.
        [&](std::size_t i) { return scores[i] >= options_.min_log_odds; }, options_.max_candidates);
  }
  detection.new_place_probability = places.new_place_probability;
  detection.places_compared = places.places_compared;
  // Verified best first, until one is accepted (as ORB-SLAM verifies its candidates):
  // verification is most of a detection's time (descriptor matching, PnP RANSAC, refinement),
  // and on a route driven again the first candidate is the place in nearly every keyframe.
  for (const PlaceCandidate& place : places.candidates) {
    LoopCandidate verified;
    if (detection.loop) {
      verified.keyframe_id = place.keyframe_id;
      verified.reason = "not verified: a candidate ranked higher was accepted";
    } else {
      verified = Verify(query, database_.Get(place.keyframe_id));
    }
    verified.probability = place.probability;
    verified.edge.probability = verified.probability;
    if (verified.accepted) detection.loop = verified.edge;
    detection.candidates.push_back(std::move(verified));
  }
  if (detection.loop && query.segment >= 0) {
    last_loops_[query.segment] = {detection.loop->query_id, detection.loop->match_id,
                                  detection.loop->T_match_query};
  }
  return detection;
}

std::string LoopDetector::Disagreement(const map::StoredKeyframe& query,
                                       const map::StoredKeyframe& candidate,
                                       const Eigen::Isometry3d& T_candidate_query) const {
  if (query.segment < 0) return "";
  // Where the odometry puts the candidate: directly within one segment; else through the query
  // segment's last loop, if the query is near it and its match shares the candidate's segment.
  Eigen::Isometry3d expected;
  double path = 0;  // travelled by the odometry that expected spans
  std::string through;
  if (query.segment == candidate.segment) {
    expected = candidate.keyframe.T_world_camera.inverse() * query.keyframe.T_world_camera;
    path = std::abs(query.path_length - candidate.path_length);
  } else {
    const auto last = last_loops_.find(query.segment);
    if (options_.loop_consistency_path <= 0 || last == last_loops_.end() ||
        !database_.Contains(last->second.query_id) || !database_.Contains(last->second.match_id)) {
      return "";
    }
    const AcceptedLoop& loop = last->second;
    const map::StoredKeyframe& loop_query = database_.Get(loop.query_id);
    const map::StoredKeyframe& loop_match = database_.Get(loop.match_id);
    const double since = std::abs(query.path_length - loop_query.path_length);
    if (loop_query.segment != query.segment || loop_match.segment != candidate.segment ||
        since > options_.loop_consistency_path) {
      return "";
    }
    expected = candidate.keyframe.T_world_camera.inverse() * loop_match.keyframe.T_world_camera *
               loop.T_match_query * loop_query.keyframe.T_world_camera.inverse() *
               query.keyframe.T_world_camera;
    path = since + std::abs(candidate.path_length - loop_match.path_length);
    through = " through the loop " + std::to_string(loop.query_id) + " -> " +
              std::to_string(loop.match_id);
  }
  const double allowance =
      std::max(options_.min_drift_allowance, options_.max_drift_fraction * path);
  const double translation_error =
      (expected.translation() - T_candidate_query.translation()).norm();
  const double rotation_error =
      RotationDegrees(expected.linear().transpose() * T_candidate_query.linear());
  if (translation_error <= allowance && rotation_error <= options_.max_rotation_drift_deg)
    return "";
  char text[200];
  std::snprintf(text, sizeof(text),
                "disagrees with the odometry%s by %.2f m, %.1f deg (drift allowance %.2f m)",
                through.c_str(), translation_error, rotation_error, allowance);
  return text;
}

LoopCandidate LoopDetector::Verify(const map::StoredKeyframe& query,
                                   const map::StoredKeyframe& candidate) const {
  LoopCandidate result;
  result.keyframe_id = candidate.keyframe.id;
  result.verified = true;
  const features::StereoFeatures& c = candidate.keyframe.features;

  // The candidate's stereo points, matched by descriptor with the ratio test.
  std::vector<int> candidate_rows;
  for (std::size_t i = 0; i < c.size(); ++i) {
    if (c.HasDepth(i)) candidate_rows.push_back(static_cast<int>(i));
  }
  cv::Mat candidate_descriptors(static_cast<int>(candidate_rows.size()), c.descriptors.cols,
                                c.descriptors.type());
  std::vector<Eigen::Vector3d> candidate_points;
  for (std::size_t k = 0; k < candidate_rows.size(); ++k) {
    c.descriptors.row(candidate_rows[k]).copyTo(candidate_descriptors.row(static_cast<int>(k)));
    candidate_points.push_back(c.points[static_cast<std::size_t>(candidate_rows[k])]);
  }
  VerificationThresholds thresholds;
  thresholds.match_ratio = options_.match_ratio;
  thresholds.pnp_kernel = options_.pnp_kernel;
  thresholds.ransac_threshold = options_.ransac_threshold;
  thresholds.ransac_iterations = options_.ransac_iterations;
  thresholds.min_inliers = options_.min_inliers;
  thresholds.min_inlier_cells = options_.min_inlier_cells;
  const ViewVerification verified = verifier_.Verify(query.keyframe.features, candidate_points,
                                                     candidate_descriptors, thresholds);
  result.matches = verified.matches;
  result.inliers = verified.inliers;
  if (!verified.passed()) {
    result.reason = verified.reason;
    return result;
  }

  // T_candidate_query: the query camera in the candidate camera's frame.
  const Eigen::Isometry3d T_candidate_query = verified.refined.T_camera_world.inverse();
  if (T_candidate_query.translation().norm() > options_.max_loop_distance) {
    char text[96];
    std::snprintf(text, sizeof(text), "cameras %.2f m apart (more than %.2f m)",
                  T_candidate_query.translation().norm(), options_.max_loop_distance);
    result.reason = text;
    return result;
  }
  if (std::string disagreement = Disagreement(query, candidate, T_candidate_query);
      !disagreement.empty()) {
    result.reason = std::move(disagreement);
    return result;
  }

  result.accepted = true;
  result.reason = "accepted";
  result.edge.query_id = query.keyframe.id;
  result.edge.match_id = candidate.keyframe.id;
  result.edge.T_match_query = T_candidate_query;
  result.edge.inliers = verified.inliers;
  for (std::size_t k = 0; k < verified.matched.size(); ++k) {
    if (!verified.refined.inlier[k]) continue;
    const auto query_key_point = static_cast<std::size_t>(verified.matched[k].queryIdx);
    const auto candidate_key_point = static_cast<std::size_t>(
        candidate_rows[static_cast<std::size_t>(verified.matched[k].trainIdx)]);
    const std::vector<std::int64_t>& query_ids = query.keyframe.map_point_ids;
    const std::vector<std::int64_t>& candidate_ids = candidate.keyframe.map_point_ids;
    if (query_key_point < query_ids.size() && candidate_key_point < candidate_ids.size() &&
        query_ids[query_key_point] >= 0 && candidate_ids[candidate_key_point] >= 0) {
      result.edge.shared_points.emplace_back(query_ids[query_key_point],
                                             candidate_ids[candidate_key_point]);
    }
  }
  result.edge.information =
      geometry::DiagonalPoseInformation(options_.translation_sigma, options_.rotation_sigma_deg);
  return result;
}

}  // namespace stereo_fabmap_slam::place_recognition
