#pragma once

#include <vector>

#include <Eigen/Geometry>
#include <opencv2/core/types.hpp>

#include "stereo_fabmap_slam/geometry/pnp_ransac.h"
#include "stereo_fabmap_slam/geometry/pose_covariance.h"
#include "stereo_fabmap_slam/geometry/stereo_camera.h"
#include "stereo_fabmap_slam/io/option_reader.h"

namespace stereo_fabmap_slam::geometry {

// The motion-only refinement that the tracker, loop verification and relocalization share.
// Read as the tracker's `refinement` subsection (tracker/refinement/...).
struct PoseRefinementOptions {
  double sigma = 1.0;   // [px] key point position noise
  int rounds = 2;       // optimise, re-classify outliers, optimise again...
  int iterations = 10;  // Levenberg-Marquardt iterations a round
  void Visit(io::OptionVisitor& visitor);
  void Validate() const;
};

// One 3-D point seen in a frame.
struct PoseObservation {
  Eigen::Vector3d world;
  double u = 0, v = 0;
  double u_right = -1;  // < 0: no stereo match in this frame
};

struct PoseRefinement {
  Eigen::Isometry3d T_camera_world = Eigen::Isometry3d::Identity();
  std::vector<bool> inlier;  // per observation
  int inliers = 0;
  // Of T_camera_world.inverse() (the camera in the world), from the final inliers and the
  // options' pixel sigma: StereoPoseCovariance.
  PoseCovariance covariance = PoseCovariance::Identity();
};

// A frame's key points (`keypoints`, with their right-image columns `u_right`, < 0 where none,
// and their stereo points `frame_points`) matched to 3-D points (match.queryIdx: key point,
// match.trainIdx: point), in the two forms PnP RANSAC and RefinePose take, in the order of
// `matches`.
struct PointMatches {
  std::vector<PnpCorrespondence> correspondences;
  std::vector<PoseObservation> observations;
};
PointMatches MatchedPoints(const std::vector<cv::KeyPoint>& keypoints,
                           const std::vector<float>& u_right,
                           const std::vector<Eigen::Vector3d>& frame_points,
                           const std::vector<Eigen::Vector3d>& points,
                           const std::vector<cv::DMatch>& matches);

// Motion-only optimisation: the camera pose that minimises the robust (Huber) stereo
// reprojection error of fixed map points. After each round every observation is classified
// again by a chi-square test at 95 % (5.99 for 2 residuals, 7.81 for 3); outliers are left out
// of the next round, and may come back if the pose moves.
// `initial_inliers` (optional) says which observations the first round uses.
PoseRefinement RefinePose(const std::vector<PoseObservation>& observations,
                          const StereoCamera& camera, const Eigen::Isometry3d& initial,
                          const PoseRefinementOptions& options,
                          const std::vector<bool>* initial_inliers = nullptr);

}  // namespace stereo_fabmap_slam::geometry
