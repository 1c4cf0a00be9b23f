#pragma once

#include <string>
#include <vector>

#include <Eigen/Geometry>
#include <opencv2/core.hpp>

#include "stereo_fabmap_slam/features/stereo_features.h"
#include "stereo_fabmap_slam/geometry/image_coverage.h"
#include "stereo_fabmap_slam/geometry/pnp_ransac.h"
#include "stereo_fabmap_slam/geometry/pose_refiner.h"
#include "stereo_fabmap_slam/geometry/stereo_camera.h"

namespace stereo_fabmap_slam::place_recognition {

// The thresholds of one geometric verification; loop detection and relocalization each fill
// them from their own options (loop_detection, relocalization).
struct VerificationThresholds {
  double match_ratio = 0.8;  // nearest / second nearest descriptor distance
  geometry::PnpKernel pnp_kernel = geometry::PnpKernel::kAp3p;
  double ransac_threshold = 2.0;  // [px]
  int ransac_iterations = 300;
  // Descriptor matches, RANSAC consensus and refined inliers must each reach this to go on.
  int min_inliers = 40;
  // The refined inliers must cover this many cells of a 4 x 4 grid; 0: not checked here (a
  // caller that searches for more inliers first checks the spread after, InlierCells).
  int min_inlier_cells = 0;
};

// How far a verification got: the first check that failed, or kPassed.
enum class VerificationStage {
  kTooFewMatches,     // too few key points or points, or descriptor matches below min_inliers
  kRansacFailed,      // no PnP consensus of min_inliers
  kRefinementFailed,  // the refinement kept fewer than min_inliers
  kTooLittleSpread,   // the inliers cover fewer than min_inlier_cells cells
  kPassed,
};

struct ViewVerification {
  VerificationStage stage = VerificationStage::kTooFewMatches;
  std::string reason;  // why it failed; empty when it passed
  int matches = 0;     // descriptor matches
  int inliers = 0;     // RANSAC's consensus, then the refinement's inliers
  int inlier_cells = 0;
  // The matched points as the refinement saw them, and its result: T_camera_world is the
  // points' frame in the view's camera frame (meaningful from kRefinementFailed on).
  std::vector<geometry::PoseObservation> observations;
  // Which key point of the view (queryIdx) and which point (trainIdx) each observation is.
  std::vector<cv::DMatch> matched;
  geometry::PoseRefinement refined;

  bool passed() const { return stage == VerificationStage::kPassed; }
};

// The cells of a 4 x 4 grid over the image that hold an inlier: how widely a pose is supported.
// A pose verified by inliers on one small object (a poster repeated elsewhere) covers few.
inline constexpr int kSpreadGrid = geometry::kInlierSpreadGrid;
int InlierCells(const std::vector<geometry::PoseObservation>& observations,
                const std::vector<bool>& inlier, const cv::Size& image_size);

// One geometric verification of a view against 3-D points, shared by loop detection and
// relocalization: the view's key points matched to the points by descriptor (ratio test), PnP
// RANSAC, robust refinement of the consensus, and the inliers' spread. No clock, no state.
class GeometricVerifier {
 public:
  // `descriptor_norm` and `max_descriptor_distance` describe the odometry's descriptors.
  GeometricVerifier(const geometry::StereoCamera& camera, int descriptor_norm,
                    double max_descriptor_distance)
      : camera_(camera),
        descriptor_norm_(descriptor_norm),
        max_descriptor_distance_(max_descriptor_distance) {}

  // `point_descriptors` has one row for each of the first point_descriptors.rows entries of
  // `points` (the points matched by descriptor; `points` may hold more after them).
  ViewVerification Verify(const features::StereoFeatures& view,
                          const std::vector<Eigen::Vector3d>& points,
                          const cv::Mat& point_descriptors,
                          const VerificationThresholds& thresholds) const;

  const geometry::StereoCamera& camera() const { return camera_; }
  int descriptor_norm() const { return descriptor_norm_; }
  double max_descriptor_distance() const { return max_descriptor_distance_; }

 private:
  geometry::StereoCamera camera_;
  int descriptor_norm_;
  double max_descriptor_distance_;
};

}  // namespace stereo_fabmap_slam::place_recognition
