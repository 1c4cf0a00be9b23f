#pragma once

#include <functional>
#include <ostream>
#include <string>
#include <vector>

#include <Eigen/Geometry>

#include "stereo_fabmap_slam/features/stereo_features.h"
#include "stereo_fabmap_slam/geometry/pnp_ransac.h"
#include "stereo_fabmap_slam/geometry/pose_refiner.h"
#include "stereo_fabmap_slam/geometry/stereo_camera.h"

namespace stereo_fabmap_slam::evaluation {

// The thesis' PnP kernel study: one reference frame's stereo points, a test frame's key points
// matched to them by descriptor, and every kernel inside the same RANSAC (same threshold,
// iterations, confidence and seed), with and without the robust pose refinement that odometry
// and relocalization run after it.
struct PnpStudyOptions {
  // Ratio test of the test frame's descriptors against the reference's stereo points.
  double match_ratio = 0.8;
  // The kernel field is overwritten by each kernel in turn; everything else is shared.
  geometry::PnpRansacOptions ransac;
  geometry::PoseRefinementOptions refinement;
  // An estimate is a success when its consensus (RANSAC's, or the refinement's inliers) holds at
  // least this many correspondences: below it the relocalizer would reject the pose too.
  int min_inliers = 20;

  void Validate() const;  // throws std::invalid_argument
};

// Pose error of an estimate against the truth, both T_camera_reference (the test camera from
// the reference camera frame). The translation error is the distance between the estimated and
// the true position of the test camera in the reference frame, the rotation error the angle of
// the rotation between the two orientations.
struct PoseError {
  double translation_m = 0;
  double rotation_deg = 0;
};
PoseError ComparePoses(const Eigen::Isometry3d& estimated_T_camera_reference,
                       const Eigen::Isometry3d& true_T_camera_reference);

// One kernel on one reference-test pair.
struct PnpTrial {
  geometry::PnpKernel kernel = geometry::PnpKernel::kAp3p;
  bool refined = false;
  double distance_m = 0;  // true distance between the reference and the test camera
  int matches = 0;        // descriptor matches given to RANSAC
  int inliers = 0;        // of the estimate (after refinement when refined)
  bool success = false;
  PoseError error;     // meaningful on success only
  double time_ms = 0;  // RANSAC, plus the refinement when refined; spent on failures too
};

// Descriptor matches of the test frame's key points (query) to the reference frame's stereo
// points (train), in the two forms RANSAC and the refinement take. The 3-D points are in the
// reference camera frame; each correspondence carries the test frame's own stereo point where it
// has one (the UMEYAMA kernel's input).
geometry::PointMatches MatchToReference(const features::StereoFeatures& reference,
                                        const features::StereoFeatures& test, int descriptor_norm,
                                        double max_descriptor_distance, double match_ratio);

// Milliseconds on a monotonic clock; the library never reads one itself.
using Clock = std::function<double()>;

// Runs each kernel in `kernels` on the same matches, in that order; returns two trials per
// kernel (without refinement, then with it). The refined trial refines the unrefined trial's
// pose from its RANSAC inliers, so the two differ only by the refinement. A kernel that throws
// (OpenCV rejects a configuration) counts as a failed estimate.
std::vector<PnpTrial> RunPnpKernels(const geometry::PointMatches& matches,
                                    const geometry::StereoCamera& camera,
                                    const Eigen::Isometry3d& true_T_camera_reference,
                                    const std::vector<geometry::PnpKernel>& kernels,
                                    const PnpStudyOptions& options, const Clock& clock);

// Every kernel the package offers, in the order of geometry::kPnpKernelNames.
std::vector<geometry::PnpKernel> AllPnpKernels();

// Trials pooled per kernel x refined (x distance bin). Errors are averaged over the successful
// trials only (a failed estimate has no pose to measure); times over all trials. Standard
// deviations are sample deviations (n - 1); with no success the error fields are NaN, with one
// value its deviation is 0.
struct PnpStatistics {
  geometry::PnpKernel kernel = geometry::PnpKernel::kAp3p;
  bool refined = false;
  double distance_m = 0;  // bin centre; unused in a summary
  int trials = 0;
  int successes = 0;
  double translation_error_mean_m = 0, translation_error_std_m = 0;
  double rotation_error_mean_deg = 0, rotation_error_std_deg = 0;
  double time_mean_ms = 0, time_std_ms = 0;

  double success_fraction() const { return trials > 0 ? double(successes) / trials : 0.0; }
};

// Bins of `bin_width` metres by distance: trial distance d falls in bin floor(d / bin_width),
// centred at (bin + 0.5) * bin_width. Rows ordered by kernel (kPnpKernelNames order),
// unrefined before refined, then by distance; only bins holding trials appear.
// Throws std::invalid_argument for a bin width <= 0.
std::vector<PnpStatistics> AggregatePnpTrials(const std::vector<PnpTrial>& trials,
                                              double bin_width);
// One row per kernel x refined, over all distances: the thesis' table.
std::vector<PnpStatistics> SummarizePnpTrials(const std::vector<PnpTrial>& trials);

// pnp.csv (with_distance) and pnp_summary.csv (without): the header line, then rows of one
// sequence. The columns are read by the evaluation report; keep them as they are.
void WritePnpCsvHeader(std::ostream& out, bool with_distance);
void WritePnpCsvRows(std::ostream& out, const std::string& sequence,
                     const std::vector<PnpStatistics>& rows, bool with_distance);
// A table for people: one line per row, errors in cm and degrees, success in percent.
void PrintPnpTable(std::ostream& out, const std::string& title,
                   const std::vector<PnpStatistics>& rows, bool with_distance);

}  // namespace stereo_fabmap_slam::evaluation
