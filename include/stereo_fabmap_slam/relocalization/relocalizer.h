#pragma once

#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include <Eigen/Geometry>
#include <opencv2/core.hpp>

#include "stereo_fabmap_slam/features/stereo_features.h"
#include "stereo_fabmap_slam/geometry/stereo_camera.h"
#include "stereo_fabmap_slam/map/keyframe_database.h"
#include "stereo_fabmap_slam/place_recognition/geometric_verification.h"
#include "stereo_fabmap_slam/place_recognition/loop_detector.h"
#include "stereo_fabmap_slam/relocalization/relocalization_options.h"

namespace stereo_fabmap_slam::relocalization {

// How far an attempt got; a failure names the furthest stage any candidate reached.
enum class RelocalizationStatus {
  kSuccess,
  kEmptyMap,            // no keyframe to relocalize against
  kNoCandidate,         // FAB-MAP proposed nothing (no words, or no keyframe allowed)
  kTooFewMatches,       // descriptor matches below min_inliers
  kRansacFailed,        // no consensus of min_inliers
  kVerificationFailed,  // too few inliers after refinement and guided search, or too little spread
};
const char* RelocalizationStatusName(RelocalizationStatus status);

struct Relocalization {
  RelocalizationStatus status = RelocalizationStatus::kNoCandidate;
  std::string reason;             // what failed, or "relocalized"
  std::int64_t keyframe_id = -1;  // the keyframe the frame was found against
  // The frame's camera in that keyframe's camera frame; the caller maps it (T_map_keyframe).
  Eigen::Isometry3d T_keyframe_camera = Eigen::Isometry3d::Identity();
  int matches = 0;         // descriptor matches to the keyframe's stereo points
  int inliers = 0;         // after the guided search and refinement
  int inlier_cells = 0;    // of 16
  double probability = 0;  // FAB-MAP's posterior of the keyframe
  int candidates = 0;      // keyframes verified

  bool success() const { return status == RelocalizationStatus::kSuccess; }
};

// Finds one frame in the keyframe map, with no prior on its pose: FAB-MAP's best keyframes among
// those `allowed` (several, not only the best), then for each: descriptor matches to its stereo
// points, PnP RANSAC, robust refinement, a guided search by projection of its and its segment
// neighbours' points for what the descriptor matching missed, refinement again, and acceptance on
// an inlier count and their spread over the image. The first candidate (in FAB-MAP's order) that
// passes wins; a failure reports the candidate that got furthest. Stateless between calls; no
// clock.
class Relocalizer {
 public:
  using KeyframeFilter = std::function<bool(const map::StoredKeyframe&)>;

  // `descriptor_norm` and `max_descriptor_distance` describe the odometry's descriptors (the
  // keyframes' and the frame's). Throws std::invalid_argument for bad options.
  Relocalizer(const RelocalizerOptions& options, const geometry::StereoCamera& camera,
              int descriptor_norm, double max_descriptor_distance);

  // `frame`: the odometry's stereo features of the frame; `words`: its place words
  // (LoopDetector::Words of its place descriptors). `segment`: the frame's odometry segment, if
  // its keyframes are in the map's database: candidates are then ranked by the segment's chain
  // of keyframes followed by this view (LoopDetector::SequenceCandidates), not by this view
  // alone; -1: this view alone (a lost camera with no segment behind it, a check of one view).
  Relocalization Relocalize(const features::StereoFeatures& frame, const std::vector<int>& words,
                            const place_recognition::LoopDetector& map,
                            const KeyframeFilter& allowed, std::int64_t segment = -1) const;

  const RelocalizerOptions& options() const { return options_; }

 private:
  // The candidate's stereo points and its neighbours', in the candidate's camera frame.
  struct PointSet {
    std::vector<Eigen::Vector3d> points;
    cv::Mat descriptors;       // one row per point
    int candidate_points = 0;  // the first ones are the candidate's own
  };
  PointSet GatherPoints(const map::KeyframeDatabase& database,
                        const map::StoredKeyframe& candidate) const;
  Relocalization Verify(const features::StereoFeatures& frame, const PointSet& points) const;

  RelocalizerOptions options_;
  geometry::StereoCamera camera_;
  int descriptor_norm_;
  double max_descriptor_distance_;
  place_recognition::GeometricVerifier verifier_;
};

}  // namespace stereo_fabmap_slam::relocalization
