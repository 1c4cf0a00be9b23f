#pragma once

#include <cstdint>
#include <vector>

#include <Eigen/Geometry>

#include "stereo_fabmap_slam/geometry/stereo_camera.h"

namespace stereo_fabmap_slam::evaluation {

// The thesis' relevance of a keyframe to a view: the share of the keyframe's 3-D points (in the
// keyframe's camera frame) that, carried by the ground-truth relative pose into the view's
// camera, lie in front of it and project inside its image. It asks whether the view sees what
// the keyframe saw, whatever the relocalizer makes of it. 0 for a keyframe without points.
double VisibleFraction(const std::vector<Eigen::Vector3d>& keyframe_points,
                       const Eigen::Isometry3d& T_view_keyframe,
                       const geometry::StereoCamera& camera);

// One test frame of the relocalization study (mapping off).
struct RelocalizationTrial {
  double timestamp = 0;  // [s]
  // The largest VisibleFraction over the map's keyframes: the frame is relevant at every
  // threshold tau up to this value.
  double relevance = 0;
  bool estimated = false;  // the relocalizer returned a pose
  std::int64_t keyframe_id = -1;
  // Distance between the estimated and the ground-truth translation from the keyframe the pose
  // was found against to the frame [m]; meaningful when estimated.
  double error_m = 0;
  double estimated_distance_m = 0;  // length of that estimated translation [m]
};

// Recall(tau, d_max): the relevant frames (relevance >= tau) relocalized with an error of at
// most d_max, over the relevant frames; 0 when no frame is relevant.
double RelocalizationRecall(const std::vector<RelocalizationTrial>& trials, double tau,
                            double max_error_m);

struct RelocalizationSummary {
  int test_frames = 0;
  int relevant_frames = 0;               // at tau
  int estimated_frames = 0;              // with a pose, relevant or not
  double recall = 0;                     // at tau and d_max
  double error_below_10cm_fraction = 0;  // of the estimates; 0 without any
  double error_median_m = 0;             // of the estimates; NaN without any
  int wrong_estimates = 0;               // estimates with an error above d_max
};

RelocalizationSummary SummarizeRelocalization(const std::vector<RelocalizationTrial>& trials,
                                              double tau, double max_error_m);

}  // namespace stereo_fabmap_slam::evaluation
