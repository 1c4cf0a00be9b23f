#include "stereo_fabmap_slam/relocalization/relocalizer.h"

#include <algorithm>
#include <cstdio>
#include <limits>
#include <unordered_map>
#include <unordered_set>

#include "stereo_fabmap_slam/features/feature_factory.h"
#include "stereo_fabmap_slam/features/keypoint_grid.h"
#include "stereo_fabmap_slam/geometry/pose_refiner.h"

namespace stereo_fabmap_slam::relocalization {
namespace {

constexpr int kSearchCell = 16;  // [px] cells of the key point grid for the guided search

// Order of the stages: a failure reports the candidate that got furthest.
int Progress(RelocalizationStatus status) {
  switch (status) {
    case RelocalizationStatus::kEmptyMap:
    case RelocalizationStatus::kNoCandidate:
      return 0;
    case RelocalizationStatus::kTooFewMatches:
      return 1;
    case RelocalizationStatus::kRansacFailed:
      return 2;
    case RelocalizationStatus::kVerificationFailed:
      return 3;
    case RelocalizationStatus::kSuccess:
      return 4;
  }
  return 0;
}

bool Better(const Relocalization& a, const Relocalization& b) {
  return Progress(a.status) > Progress(b.status) ||
         (Progress(a.status) == Progress(b.status) && a.inliers > b.inliers);
}

}  // namespace

const char* RelocalizationStatusName(RelocalizationStatus status) {
  switch (status) {
    case RelocalizationStatus::kSuccess:
      return "success";
    case RelocalizationStatus::kEmptyMap:
      return "empty map";
    case RelocalizationStatus::kNoCandidate:
      return "no candidate";
    case RelocalizationStatus::kTooFewMatches:
      return "too few matches";
    case RelocalizationStatus::kRansacFailed:
      return "RANSAC failed";
    case RelocalizationStatus::kVerificationFailed:
      return "verification failed";
  }
  return "?";
}

Relocalizer::Relocalizer(const RelocalizerOptions& options, const geometry::StereoCamera& camera,
                         int descriptor_norm, double max_descriptor_distance)
    : options_((options.Validate(), options)),
      camera_(camera),
      descriptor_norm_(descriptor_norm),
      max_descriptor_distance_(max_descriptor_distance),
      verifier_(camera, descriptor_norm, max_descriptor_distance) {}

Relocalization Relocalizer::Relocalize(const features::StereoFeatures& frame,
                                       const std::vector<int>& words,
                                       const place_recognition::LoopDetector& map,
                                       const KeyframeFilter& allowed, std::int64_t segment) const {
  Relocalization best;
  if (map.database().empty()) {
    best.status = RelocalizationStatus::kEmptyMap;
    best.reason = "the map is empty";
    return best;
  }
  if (words.empty()) {
    best.reason = "the frame has no place words";
    return best;
  }
  // In a building of look-alike corridors one view's best places are often look-alikes that
  // verify (identical doors and lights); the chain of the segment's keyframes picks the place
  // out, as it does for loops.
  const place_recognition::PlaceQuery places =
      segment >= 0 ? map.SequenceCandidates(words, allowed, segment, options_.max_candidates)
                   : map.Candidates(words, allowed, options_.max_candidates, 0.0);
  if (places.places_compared == 0) {
    best.reason = "no keyframe of the map to compare with";
    return best;
  }
  best.reason = "FAB-MAP proposed no keyframe";
  int verified = 0;
  for (const place_recognition::PlaceCandidate& candidate : places.candidates) {
    const map::StoredKeyframe& keyframe = map.database().Get(candidate.keyframe_id);
    Relocalization attempt = Verify(frame, GatherPoints(map.database(), keyframe));
    attempt.keyframe_id = candidate.keyframe_id;
    attempt.probability = candidate.probability;
    if (verified == 0 || Better(attempt, best)) best = std::move(attempt);
    ++verified;
    // The first verified candidate in FAB-MAP's order wins: verification is strict enough to
    // trust it, and stopping keeps the typical attempt to one candidate's cost.
    if (best.success()) break;
  }
  best.candidates = verified;
  return best;
}

Relocalizer::PointSet Relocalizer::GatherPoints(const map::KeyframeDatabase& database,
                                                const map::StoredKeyframe& candidate) const {
  // The candidate, then its neighbours on the same odometry segment, nearest first.
  std::vector<const map::StoredKeyframe*> keyframes{&candidate};
  const auto& all = database.keyframes();
  const auto at = all.find(candidate.keyframe.id);
  auto before = at, after = at;
  for (int k = 0; k < options_.neighbours; ++k) {
    if (before != all.begin() && std::prev(before)->second.segment == candidate.segment) {
      --before;
      keyframes.push_back(&before->second);
    }
    if (std::next(after) != all.end() && std::next(after)->second.segment == candidate.segment) {
      ++after;
      keyframes.push_back(&after->second);
    }
  }

  PointSet set;
  std::vector<std::pair<const cv::Mat*, int>> rows;
  std::unordered_set<std::int64_t> seen;  // map points already taken from a nearer keyframe
  const Eigen::Isometry3d T_candidate_world = candidate.keyframe.T_world_camera.inverse();
  for (const map::StoredKeyframe* stored : keyframes) {
    const map::Keyframe& keyframe = stored->keyframe;
    const Eigen::Isometry3d T_candidate_keyframe = T_candidate_world * keyframe.T_world_camera;
    for (std::size_t i = 0; i < keyframe.features.size(); ++i) {
      if (!keyframe.features.HasDepth(i)) continue;
      const std::int64_t id =
          i < keyframe.map_point_ids.size() ? keyframe.map_point_ids[i] : std::int64_t{-1};
      if (id >= 0 && !seen.insert(id).second) continue;
      set.points.push_back(T_candidate_keyframe * keyframe.features.points[i]);
      if (stored == &candidate) ++set.candidate_points;
      rows.emplace_back(&keyframe.features.descriptors, static_cast<int>(i));
    }
  }
  if (!rows.empty()) {
    const cv::Mat& first = *rows.front().first;
    set.descriptors.create(static_cast<int>(rows.size()), first.cols, first.type());
    for (std::size_t k = 0; k < rows.size(); ++k) {
      rows[k].first->row(rows[k].second).copyTo(set.descriptors.row(static_cast<int>(k)));
    }
  }
  return set;
}

Relocalization Relocalizer::Verify(const features::StereoFeatures& frame,
                                   const PointSet& set) const {
  Relocalization result;
  // 1-2. Descriptor matches between the frame and the candidate's own points (the first
  // candidate_points of the set), PnP RANSAC, and the robust refinement of its consensus.
  place_recognition::VerificationThresholds thresholds;
  thresholds.match_ratio = options_.match_ratio;
  thresholds.pnp_kernel = options_.pnp_kernel;
  thresholds.ransac_threshold = options_.ransac_threshold;
  thresholds.ransac_iterations = options_.ransac_iterations;
  thresholds.min_inliers = options_.min_ransac_inliers;
  const place_recognition::ViewVerification verified = verifier_.Verify(
      frame, set.points, set.descriptors.rowRange(0, set.candidate_points), thresholds);
  result.matches = verified.matches;
  result.inliers = verified.inliers;
  result.reason = verified.reason;
  switch (verified.stage) {
    case place_recognition::VerificationStage::kTooFewMatches:
      result.status = RelocalizationStatus::kTooFewMatches;
      return result;
    case place_recognition::VerificationStage::kRansacFailed:
      result.status = RelocalizationStatus::kRansacFailed;
      return result;
    case place_recognition::VerificationStage::kRefinementFailed:
    case place_recognition::VerificationStage::kTooLittleSpread:
      result.status = RelocalizationStatus::kVerificationFailed;
      return result;
    case place_recognition::VerificationStage::kPassed:
      break;
  }
  const geometry::PoseRefinement& refined = verified.refined;
  const geometry::PoseRefinementOptions refinement;

  // 3. Guided search: each point, projected with the refined pose, takes its best key point
  // nearby; each key point keeps its best point.
  const features::KeypointGrid grid(frame.keypoints, camera_.size, kSearchCell);
  struct Found {
    std::size_t point;
    double distance;
  };
  std::unordered_map<int, Found> by_keypoint;
  for (std::size_t p = 0; p < set.points.size(); ++p) {
    const Eigen::Vector3d c = refined.T_camera_world * set.points[p];
    if (c.z() < 0.05) continue;
    const double u = camera_.fx * c.x() / c.z() + camera_.cx;
    const double v = camera_.fy * c.y() / c.z() + camera_.cy;
    if (u < 0 || v < 0 || u >= camera_.size.width || v >= camera_.size.height) continue;
    double best = std::numeric_limits<double>::max(), second = best;
    int best_index = -1;
    grid.ForEachWithin(u, v, options_.search_radius, [&](int i) {
      const double distance = features::DescriptorDistance(set.descriptors, static_cast<int>(p),
                                                           frame.descriptors, i, descriptor_norm_);
      if (distance < best) {
        second = best;
        best = distance;
        best_index = i;
      } else if (distance < second) {
        second = distance;
      }
    });
    if (best_index < 0 || best > max_descriptor_distance_ || best > options_.match_ratio * second) {
      continue;
    }
    const auto [it, inserted] = by_keypoint.try_emplace(best_index, Found{p, best});
    if (!inserted && best < it->second.distance) it->second = Found{p, best};
  }
  std::vector<int> keypoints;
  for (const auto& entry : by_keypoint) keypoints.push_back(entry.first);
  std::sort(keypoints.begin(), keypoints.end());  // deterministic order for the refinement
  std::vector<geometry::PoseObservation> guided;
  for (const int i : keypoints) {
    const cv::Point2f& pixel = frame.keypoints[static_cast<std::size_t>(i)].pt;
    guided.push_back({set.points[by_keypoint.at(i).point], pixel.x, pixel.y,
                      frame.u_right[static_cast<std::size_t>(i)]});
  }
  const geometry::PoseRefinement final_pose =
      geometry::RefinePose(guided, camera_, refined.T_camera_world, refinement);

  // 4. Acceptance: enough inliers, spread over the image.
  result.inliers = final_pose.inliers;
  result.inlier_cells = place_recognition::InlierCells(guided, final_pose.inlier, camera_.size);
  result.T_keyframe_camera = final_pose.T_camera_world.inverse();
  if (result.inliers < options_.min_inliers) {
    result.status = RelocalizationStatus::kVerificationFailed;
    result.reason = std::to_string(result.inliers) + " inliers after the guided search (" +
                    std::to_string(options_.min_inliers) + " needed)";
    return result;
  }
  if (result.inlier_cells < options_.min_inlier_cells) {
    result.status = RelocalizationStatus::kVerificationFailed;
    result.reason =
        "inliers cover only " + std::to_string(result.inlier_cells) + " of " +
        std::to_string(place_recognition::kSpreadGrid * place_recognition::kSpreadGrid) +
        " image cells";
    return result;
  }
  result.status = RelocalizationStatus::kSuccess;
  result.reason = "relocalized";
  return result;
}

}  // namespace stereo_fabmap_slam::relocalization
