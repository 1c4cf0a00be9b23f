#pragma once

#include "stereo_fabmap_slam/io/option_reader.h"

namespace stereo_fabmap_slam::backend {

struct BundleAdjustmentOptions {
  static constexpr char kSection[] = "backend";

  int window = 15;          // keyframes optimised together
  int fixed_keyframes = 1;  // the oldest keyframes of the window are held fixed (the gauge)
  int iterations = 10;      // Levenberg-Marquardt iterations a round
  // [sigma^2] > 0: a solve ends after an accepted step that lowered the cost (half the sum of
  // the squared, sigma-scaled residuals) by less than this (geometry::SmallStepStop), sparing the
  // linear solve of a step that Ceres' own rule (function_tolerance, 1e-6 of the cost) would
  // mostly reject. Measured at 0.02 (a step of Mahalanobis length 0.2): on the hall routes, MH01
  // and V101 the same trajectories to the printed digit and the 4-lap route's adjustment
  // 33.7-33.9 -> 30.2-31.0 ms a keyframe, because there each step's decrease is 20-100 times below
  // the one before it; but in the office world convergence is slow (a decrease halves from step to
  // step), the rule stops 10-15 % of the solves early by up to 0.02 sigma^2, and two office routes
  // of three ended worse (docs/benchmarks.md). So 0, Ceres' rule only, stays the default.
  double converged_step_decrease = 0;
  // Optimise, remove outlier observations, optimise again: at most this many rounds, and a next
  // one only if the last removed observations (otherwise it would start at its optimum).
  int rounds = 2;
  double sigma = 1.0;  // [px] key point position noise
  int threads = 1;
  // Also the covariance of each step between consecutive keyframes of the window, at the
  // optimum (WindowCovariance; about 4 % of the adjustment's time). The mapping stage turns it on
  // when the pose graph weighs its odometry edges by them
  // (PoseGraphOptions::odometry_covariance_scale).
  bool step_covariances = false;

  void Visit(io::OptionVisitor& visitor);
  void Validate() const;
};

struct PoseGraphOptions {
  static constexpr char kSection[] = "pose_graph";

  // Noise of the odometry between consecutive keyframes. Stereo odometry with local bundle
  // adjustment drifts about 1 % of the distance travelled and keyframes are some 0.2 - 1 m apart,
  // i.e. millimetres to a centimetre per edge: 2 cm leaves room for the worse steps (fast motion,
  // few features) without letting a loop edge of centimetre accuracy be outvoted by a long chain.
  double odometry_translation_sigma = 0.02;  // [m]
  // Heading error is what turns into most of the position drift; 0.1 degrees per keyframe random
  // walks to ~1 degree over 100 keyframes, what stereo odometry shows over a few tens of metres.
  double odometry_rotation_sigma_deg = 0.1;  // [deg]
  // > 0: an odometry edge whose step the bundle adjustment's window estimated carries that
  // covariance times this instead of the sigmas above (BundleAdjustmentOptions::
  // step_covariances). The estimate is right for the step alone (1 is its scale: on the rendered
  // routes the steps' length and angle errors are 0.6-1.4 of its sigmas, RMS), but consecutive
  // steps share points and biases, which the graph's independent edges cannot say; with 1 the
  // 4-lap hall route and the office loop close far better and the kidnaps worse
  // (docs/benchmarks.md), so 0, the fixed sigmas, stays the default.
  double odometry_covariance_scale = 0;
  // With odometry_covariance_scale > 0: each edge's covariance is the step's plus the fixed
  // sigmas' (a floor for what the step's own estimate cannot hold: the error it shares with the
  // steps around it). Measured on ten routes: within 0.2 % of the fixed sigmas on the hall but the
  // 4-lap route (+2 %), the office loops 24 % and 2 % better (docs/benchmarks.md).
  bool odometry_covariance_plus_fixed = false;
  // Cauchy loss on loop edges, in units of the whitened residual (standard deviations). Cauchy
  // rather than Huber because its pull falls off as 1/residual: a wrong loop that survived
  // place recognition and geometric verification (repeated structure) ends up metres, i.e.
  // hundreds of sigmas, away and then barely pulls, where Huber would still pull with a constant
  // force. 3.5 is the 95 % quantile of a 6-dof chi-square (sqrt(12.6)): correct loops after
  // convergence lie mostly inside it and keep nearly full weight. The flip side: a correct loop
  // that disagrees with the odometry by many combined sigmas is treated as wrong too, so the
  // odometry sigmas must not be set far below the real drift.
  double loop_loss_scale = 3.5;
  // Levenberg-Marquardt iterations an Optimize(); from the previous solution a new loop needs a
  // handful, closing many loops over a long drift at once about 10.
  int iterations = 30;
  // A new loop whose squared whitened error at the current map poses is below this agrees with
  // the map: 16.8 is the 99 % quantile of a 6-dof chi-square, so a correct loop edge with the
  // configured uncertainty passes 99 times in 100 when the map is right, and a loop that has
  // drift to remove (a first closure, or one after a long stretch without loops) does not.
  double consistent_loop_chi2 = 16.8;
  // How many keyframes a loop that agrees with the map moves: those nearest its two keyframes
  // in the graph (over odometry and loop edges), the rest held fixed. Such a loop corrects the
  // map within a few of its sigmas, and the correction fades along the chains; 200 keyframes
  // take in tens of metres of odometry around it and the keyframes of the earlier passes that
  // loops joined to it, and solve in tens of milliseconds however large the map (a 2,100-keyframe
  // graph with 2,000 loops, rendered laps: 0.7 s for the whole, 30 ms for 200, the same
  // accuracy; the 10-minute rendered route of make bench-long: ATE 1.23 cm against 1.15 cm).
  // 0: every Optimize() optimises the whole graph.
  int local_keyframes = 200;
  // A tracking loss's gap (PoseGraph::AddGap): the odometry went on by its motion model from the
  // last keyframe before the loss to the first after it. Gaps longer than this [s] are left out:
  // beyond a second the motion model guesses (and a camera carried elsewhere in the dark would
  // be joined with an uncertainty too large for the check below to refuse it).
  double gap_max_seconds = 1.0;
  // The gap's standard deviation grows with its length: the odometry's per-edge sigmas plus
  // these rates per second. A quarter of a walking speed (1 m/s) and 10 degrees a second bound
  // how far the velocity and turn rate of a hand-held, walking or flying camera change within a
  // second, which a constant-velocity model misses (a corridor end's turn: ~45 deg/s at most).
  double gap_translation_sigma_per_second = 0.25;   // [m/s]
  double gap_rotation_sigma_deg_per_second = 10.0;  // [deg/s]
  // A gap joins the pose graph once a loop or relocalization joins its two segments' pieces, and
  // stays only if, optimised with it, its squared whitened error is below this (16.8: the 99 %
  // quantile of a 6-dof chi-square): what the motion model bridged agrees with the map. A
  // kidnap (the camera jumped metres) is thousands of sigmas off and is taken out again.
  double gap_chi2 = 16.8;

  void Visit(io::OptionVisitor& visitor);
  void Validate() const;
};

// Bundle adjustment of the whole map after loop closing (GlobalRefinement).
struct GlobalRefinementOptions {
  static constexpr char kSection[] = "global_refinement";

  // When the whole map is refined: after every optimisation of the whole pose graph (a loop
  // that disagreed with the map: a closure that removed drift; the mapping stage, in both
  // drivers), and at the end of an offline run (run_dataset). Both off: measured on ten routes
  // the refinement is better on some and worse on others (docs/benchmarks.md).
  bool after_loop_closing = false;
  bool at_end = false;
  // Levenberg-Marquardt iterations a round; a round more if the first found outliers
  // (observations beyond the 95 % chi-square, as the windowed adjustment).
  int iterations = 20;
  int rounds = 2;
  // An odometry edge of the pose graph (with the graph's information) joins the problem only for
  // a step whose two keyframes share fewer points than this: where they share enough, the
  // points measure the step themselves (the edge is the odometry's summary of the same points,
  // and with the graph's fixed sigmas would hold every step equally stiff again); where they
  // share few or none (blank walls, a tracking loss's gap) the edge keeps the step from
  // floating. Three points fix a pose at the least; 10 leave room for noise and the outlier
  // test's removals. 0: no odometry edges at all.
  int odometry_edge_below_shared_points = 10;
  // Loop and relocalization edges' information times this.
  double loop_information_scale = 1.0;
  // The map points a loop's verification matched on both passes become one point, seen from
  // both (the loops' shared points), so the points join the passes as well as the loop edges.
  bool fuse_loop_points = true;
  // ...if the two points lie within this of each other in the map [m]. After loop closing the
  // passes agree to the loops' few centimetres; the points' own stereo error is some centimetres
  // at 3-4 m (0.2 px of disparity); a verification inlier matched to a look-alike (the next door
  // of a corridor) lies a door's width or more away. Without it, such pairs chained groups across
  // the office loop s11 (14.6 cm against 4.3).
  double fuse_max_distance = 0.2;
  int threads = 1;

  void Visit(io::OptionVisitor& visitor);
  void Validate() const;
};

}  // namespace stereo_fabmap_slam::backend
