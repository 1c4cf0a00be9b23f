#include "stereo_fabmap_slam/place_recognition/geometric_verification.h"

#include "stereo_fabmap_slam/features/descriptor_matching.h"
#include "stereo_fabmap_slam/geometry/image_coverage.h"

namespace stereo_fabmap_slam::place_recognition {
namespace {

// Below this many key points or points, PnP RANSAC has nothing to choose from.
constexpr std::size_t kFewestPoints = 6;

}  // namespace

int InlierCells(const std::vector<geometry::PoseObservation>& observations,
                const std::vector<bool>& inlier, const cv::Size& image_size) {
  std::vector<Eigen::Vector2d> pixels;
  for (std::size_t k = 0; k < observations.size(); ++k) {
    if (inlier[k]) pixels.emplace_back(observations[k].u, observations[k].v);
  }
  return geometry::OccupiedCells(pixels, image_size, kSpreadGrid);
}

ViewVerification GeometricVerifier::Verify(const features::StereoFeatures& view,
                                           const std::vector<Eigen::Vector3d>& points,
                                           const cv::Mat& point_descriptors,
                                           const VerificationThresholds& thresholds) const {
  ViewVerification result;
  if (static_cast<std::size_t>(point_descriptors.rows) < kFewestPoints ||
      view.size() < kFewestPoints) {
    result.reason = "too few key points";
    return result;
  }
  std::vector<cv::DMatch> matches =
      features::RatioTestMatches(view.descriptors, point_descriptors, descriptor_norm_,
                                 max_descriptor_distance_, thresholds.match_ratio);
  geometry::PointMatches matched =
      geometry::MatchedPoints(view.keypoints, view.u_right, view.points, points, matches);
  result.matches = static_cast<int>(matched.correspondences.size());
  if (result.matches < thresholds.min_inliers) {
    result.reason = "only " + std::to_string(result.matches) + " descriptor matches";
    return result;
  }

  geometry::PnpRansacOptions ransac_options;
  ransac_options.kernel = thresholds.pnp_kernel;
  ransac_options.reprojection_threshold = thresholds.ransac_threshold;
  ransac_options.max_iterations = thresholds.ransac_iterations;
  const geometry::PnpResult ransac = geometry::SolvePnpRansac(
      matched.correspondences, camera_, ransac_options, Eigen::Isometry3d::Identity());
  result.inliers = static_cast<int>(ransac.inliers.size());
  if (!ransac.success || result.inliers < thresholds.min_inliers) {
    result.stage = VerificationStage::kRansacFailed;
    result.reason = "RANSAC found " + std::to_string(result.inliers) + " inliers";
    return result;
  }

  std::vector<bool> initial(matched.correspondences.size(), false);
  for (const int i : ransac.inliers) initial[static_cast<std::size_t>(i)] = true;
  result.observations = std::move(matched.observations);
  result.matched = std::move(matches);
  result.refined = geometry::RefinePose(result.observations, camera_, ransac.T_camera_world,
                                        geometry::PoseRefinementOptions(), &initial);
  result.inliers = result.refined.inliers;
  if (result.inliers < thresholds.min_inliers) {
    result.stage = VerificationStage::kRefinementFailed;
    result.reason = "refinement kept " + std::to_string(result.inliers) + " inliers";
    return result;
  }

  result.inlier_cells = InlierCells(result.observations, result.refined.inlier, camera_.size);
  if (result.inlier_cells < thresholds.min_inlier_cells) {
    result.stage = VerificationStage::kTooLittleSpread;
    result.reason = "inliers cover only " + std::to_string(result.inlier_cells) + " of " +
                    std::to_string(kSpreadGrid * kSpreadGrid) + " image cells";
    return result;
  }
  result.stage = VerificationStage::kPassed;
  return result;
}

}  // namespace stereo_fabmap_slam::place_recognition
