#pragma once

#include <cstdint>
#include <functional>
#include <limits>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "stereo_fabmap_slam/geometry/stereo_camera.h"
#include "stereo_fabmap_slam/map/keyframe.h"
#include "stereo_fabmap_slam/map/keyframe_database.h"
#include "stereo_fabmap_slam/map/loop_edge.h"
#include "stereo_fabmap_slam/place_recognition/fab_map.h"
#include "stereo_fabmap_slam/place_recognition/geometric_verification.h"
#include "stereo_fabmap_slam/place_recognition/place_recognition_options.h"
#include "stereo_fabmap_slam/place_recognition/sequence_score.h"
#include "stereo_fabmap_slam/place_recognition/vocabulary.h"

namespace stereo_fabmap_slam::place_recognition {

// One keyframe FAB-MAP proposed, and what verification made of it.
struct LoopCandidate {
  std::int64_t keyframe_id = -1;
  double probability = 0;  // FAB-MAP posterior
  int matches = 0;         // descriptor matches to its stereo points
  int inliers = 0;         // after RANSAC and refinement
  bool verified = false;   // false: a candidate before it was accepted, this one not tried
  bool accepted = false;
  std::string reason;  // why rejected or not verified; "accepted" otherwise
  map::LoopEdge edge;  // meaningful if accepted
};

// A keyframe FAB-MAP proposes for a view, with its posterior.
struct PlaceCandidate {
  std::int64_t keyframe_id = -1;
  double probability = 0;
};

// FAB-MAP's answer for a view over a part of the map.
struct PlaceQuery {
  std::vector<PlaceCandidate> candidates;  // best first
  double new_place_probability = 1;
  int places_compared = 0;  // keyframes the view was compared with
};

struct LoopDetection {
  std::int64_t query_id = -1;
  double new_place_probability = 1;
  int places_compared = 0;                // keyframes old enough to be loops
  std::vector<LoopCandidate> candidates;  // best first (sequence score, or posterior alone)
  // The first candidate accepted, if any; the candidates after it are not verified.
  std::optional<map::LoopEdge> loop;
};

// Loop detection over the keyframe map: every keyframe becomes one FAB-MAP place (addressed by
// keyframe id, never merged), and each new keyframe is compared with the places at least
// `min_age` older; the best candidates are verified geometrically against the candidate's stereo
// points. Owns the KeyframeDatabase, the one store of keyframes that relocalization reads too.
class LoopDetector {
 public:
  // `descriptor_norm` and `max_descriptor_distance` describe the odometry's descriptors (the
  // keyframes' features). Throws std::invalid_argument for bad options.
  LoopDetector(const LoopDetectorOptions& options, Vocabulary vocabulary, FabMap fabmap,
               const geometry::StereoCamera& camera, int descriptor_norm,
               double max_descriptor_distance);

  // The keyframe's place words. Throws std::invalid_argument when its place descriptors are not
  // of the vocabulary's type and size (a keyframe from another configuration).
  std::vector<int> Words(const map::Keyframe& keyframe) const;
  // The same for any view's place descriptors.
  std::vector<int> Words(const cv::Mat& place_descriptors) const;

  // Adds a keyframe to the map (the database, and FAB-MAP as a place); returns it as stored.
  const map::StoredKeyframe& Add(map::Keyframe keyframe);
  // The same for a keyframe whose words are known (a saved map's).
  const map::StoredKeyframe& Add(map::Keyframe keyframe, std::vector<int> words);
  // A detector with the same vocabulary, FAB-MAP model and options, and no keyframes.
  LoopDetector WithoutKeyframes() const;
  std::uint64_t vocabulary_fingerprint() const { return vocabulary_fingerprint_; }
  // Looks for a loop of a new keyframe, then (if add_to_map) adds it to the map.
  LoopDetection Process(map::Keyframe keyframe, bool add_to_map = true);
  // The same query for a keyframe already in the map (std::out_of_range for an unknown id).
  LoopDetection DetectStored(std::int64_t keyframe_id);

  // FAB-MAP's best places for a view's words among the keyframes `allowed` accepts (the
  // posterior is taken over those alone): at most max_candidates with a posterior of at least
  // min_probability and log odds against a new place of at least min_log_odds, best first.
  PlaceQuery Candidates(const std::vector<int>& words,
                        const std::function<bool(const map::StoredKeyframe&)>& allowed,
                        int max_candidates, double min_probability,
                        double min_log_odds = -std::numeric_limits<double>::infinity()) const;

  // The same for a view of odometry segment `segment` that is no keyframe (a relocalization
  // attempt), ranked as loop detection ranks that segment's keyframes: by the sequence score of
  // the segment's chain of keyframes so far followed by this view (one view alone if the chain
  // is of another segment, or sequence_length is 1). No floor: the best max_candidates.
  PlaceQuery SequenceCandidates(const std::vector<int>& words,
                                const std::function<bool(const map::StoredKeyframe&)>& allowed,
                                std::int64_t segment, int max_candidates) const;

  // The bundle adjustment moved a keyframe (odom frame).
  void UpdatePose(std::int64_t id, const Eigen::Isometry3d& T_odom_camera) {
    database_.UpdatePose(id, T_odom_camera);
  }
  const map::KeyframeDatabase& database() const { return database_; }
  // The camera and descriptors its verification works with.
  const GeometricVerifier& verifier() const { return verifier_; }

 private:
  // A query of segment -1 (not stored) has no odometry to check the verified pose against.
  LoopDetection Detect(const map::StoredKeyframe& query);
  void AddPlace(const map::StoredKeyframe& stored);
  // The last loop accepted for a query of one odometry segment.
  struct AcceptedLoop {
    std::int64_t query_id = -1;
    std::int64_t match_id = -1;
    Eigen::Isometry3d T_match_query = Eigen::Isometry3d::Identity();
  };
  LoopCandidate Verify(const map::StoredKeyframe& query,
                       const map::StoredKeyframe& candidate) const;
  // Why a verified T_candidate_query disagrees with where the odometry (and, across segments, the
  // query segment's last loop) puts the candidate; empty if it agrees or nothing can tell.
  std::string Disagreement(const map::StoredKeyframe& query, const map::StoredKeyframe& candidate,
                           const Eigen::Isometry3d& T_candidate_query) const;
  // FAB-MAP over the places `mask` flags, with each one's log odds against a new place in
  // `log_odds` (-infinity for the others); nothing to compare (no place, no word): posterior
  // all 0.
  FabMapResult CompareAllowed(const std::vector<int>& words, const std::vector<char>& mask,
                              std::vector<double>* log_odds) const;
  // Which places `allowed` accepts: one flag per FAB-MAP place.
  std::vector<char> AllowedPlaces(
      const std::function<bool(const map::StoredKeyframe&)>& allowed) const;
  // The best `max_candidates` places of `mask` by `score` that `eligible` accepts, best first
  // (equal scores in map order, so that the result is deterministic).
  PlaceQuery Ranked(const FabMapResult& result, const std::vector<char>& mask,
                    const std::vector<double>& score,
                    const std::function<bool(std::size_t)>& eligible, int max_candidates) const;

  LoopDetectorOptions options_;
  Vocabulary vocabulary_;
  FabMap fabmap_;
  GeometricVerifier verifier_;
  std::uint64_t vocabulary_fingerprint_;
  map::KeyframeDatabase database_;
  std::vector<std::int64_t> place_keyframes_;  // FAB-MAP place index -> keyframe id
  // Temporal consistency over the stored keyframes queried in order, one odometry segment at a
  // time (sequence_length 1: off).
  SequenceScore sequence_;
  std::int64_t sequence_segment_ = -1;
  std::int64_t sequence_last_id_ = -1;  // the newest keyframe in the sequence
  // By odometry segment of the query: its last accepted loop (loop_consistency_path).
  std::map<int, AcceptedLoop> last_loops_;
};

}  // namespace stereo_fabmap_slam::place_recognition
