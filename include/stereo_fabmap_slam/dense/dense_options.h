#pragma once

#include "stereo_fabmap_slam/io/option_reader.h"

namespace stereo_fabmap_slam::dense {

// Dense depth from a rectified stereo pair (OpenCV's semi-global matching), kept only where it
// is reliable: textured, consistent from left to right, not an isolated speckle, near enough.
struct StereoDepthOptions {
  static constexpr char kSection[] = "dense_depth";

  // Disparities searched, a multiple of 16. 64 px at EuRoC's focal length (458 px) and
  // baseline (0.11 m) reaches down to 0.79 m, nearer than the walls a walking or flying camera
  // passes; more costs time in proportion.
  int disparities = 64;
  // Matching window [px of the matched image, see matching_scale], odd; also the full image's
  // window of the texture floor (min_texture). 5 keeps edges sharp at 752 x 480; larger smooths
  // more. 3 at half resolution (with a 3 x 3 texture window) lost a sixth of the hall loop's
  // completeness (0.769 -> 0.631) for no better accuracy.
  int block_size = 5;
  // The best match's cost must beat the second best by this percentage (SGBM's uniqueness):
  // repeated texture (tiles, doors) gives two near-equal minima.
  int uniqueness = 10;
  // Left-right consistency: the right image's disparity at the matched pixel may differ by at
  // most this many pixels (SGBM's disp12MaxDiff); occlusions and mismatches fail it.
  int left_right_max_difference = 1;
  // Speckle filtering: connected regions of fewer pixels than this whose disparity varies by at
  // most speckle_range px are removed (isolated blobs are mismatches, real surfaces are larger).
  int speckle_window = 100;
  int speckle_range = 2;
  // Pixels whose window has a grey-level standard deviation below this carry no match: a blank
  // wall's paint varies by about 3 levels under 2 levels of camera noise.
  double min_texture = 4.0;
  // Depth beyond this [m] is dropped: its error grows with the square of the distance (at
  // 6 m a quarter pixel of disparity is 18 cm).
  double max_depth = 6.0;
  // Window [px] of the sub-pixel refinement of the matcher's disparities (DisparityRefinement),
  // odd; 0 for none. The refinement's noise falls with the window's area, its fronto-parallel
  // assumption fails on slanted surfaces as it grows: 15 px spans 10 cm at 3 m. On three routes
  // of the rendered hall, run_dataset --dense with 0 / 15: mesh median 3.15-4.18 / 2.27-2.99
  // cm, 90 % 8.57-10.63 / 7.59-9.51 cm, completeness 0.64-0.74 / 0.69-0.77; 21 px (with two
  // steps) within 0.1 cm of 15. It costs about 6 ms a keyframe whatever the window (8 ms on the
  // slower machine of 2026-12-01; docs/benchmarks.md).
  int refinement_window = 15;
  // Resolution the matcher searches at: 1 the full image, 2 half of it (both images halved by
  // OpenCV's pyramid, the disparities doubled back to full resolution; block_size then counts
  // half-resolution pixels, while disparities, speckle_window and speckle_range stay in the
  // full image's and are converted: disparities halved and rounded up to a multiple of 16, the
  // speckle window divided by 4 and the range by 2, at least 1), after which the sub-pixel
  // refinement, which must be on, corrects them at full resolution. A 5 x 5 window at half
  // resolution sees a 10 x 10 patch of the image (fewer blocks allocated on every route
  // measured: fewer mismatches, we take it), and the refinement's 15 x 15 window does the
  // sub-pixel work either way. Against 1, with run_dataset --dense on three routes of the
  // rendered hall (loop 34 s seeds 1 and 3, figure eight 40 s seed 2): depth 58-66 -> 23-28 ms
  // a keyframe; mesh median 2.27 / 2.44 / 2.99 -> 2.17 / 2.32 / 2.81 cm, 90 % 7.59 / 8.12 /
  // 9.51 -> 6.88 / 7.59 / 8.34 cm, completeness 0.770 / 0.752 / 0.690 -> 0.769 / 0.755 /
  // 0.700; per pair (dense_test) the same median disparity errors, 0.09-0.15 px
  // (docs/benchmarks.md). No coarser scale is offered: at a quarter of 752 x 480 a 5 x 5 window
  // spans 20 x 20 px, across most depth edges.
  int matching_scale = 2;
  // Steps of the sub-pixel refinement (each at most a pixel), >= 1. Two measured no better than
  // one at either scale (hall loop seed 1, scale 2: mesh 2.17 / 6.88 -> 2.22 / 7.32 cm) and cost
  // another 15 ms a keyframe (this machine).
  int refinement_steps = 1;
  // Window [px] over which the refined disparities are averaged, odd; 0 for none. Each pixel's
  // refined disparity keeps its own matching error (the refinement corrects it by its window's
  // mean residual only); the plain mean over a full window takes most of it out, and on a plane,
  // where the disparity is affine in the image, a symmetric mean is exact however slanted the
  // plane is. (A gradient-weighted mean, as a one-disparity-per-window Lucas-Kanade gives, is
  // not: it lost a third of MH01's surface to the one-pixel check.) On the rendered hall
  // (dense_test): median disparity error 0.090 / 0.146 / 0.116 -> 0.057 / 0.095 / 0.075 px, 90 %
  // 0.317 / 0.486 / 0.451 -> 0.208 / 0.362 / 0.394 px; the rendered routes' meshes in
  // docs/benchmarks.md. 15 px, the refinement's window: 7 px left 0.074 / 0.120 / 0.094 px.
  int smoothing_window = 15;
  // A pixel whose window mean differs from its own refined disparity by more than this [px]
  // keeps its own: the window straddles a depth edge or a fold, where the mean is of two
  // surfaces. 0.5 px: above the refined disparities' 90th percentile error on surfaces (0.32-0.49
  // px), below the one-pixel step the refinement itself allows (1 px measured the same).
  double smoothing_agreement = 0.5;
  // Depth edges [px of disparity]: a pixel whose disparity differs from a neighbour's (of the 8)
  // by more than edge_jump marks an edge, and every pixel within edge_radius of one loses its
  // disparity (ClearDisparityEdges); edge_jump 0 for none. Beside an occluding edge the
  // matcher's and the refinement's windows hold both surfaces: the pixels there take a
  // disparity between the two or the nearer surface's ("foreground fattening"), and fused they
  // float beside pillars and boxes. A plane's disparity changes by b |n_xy| / D a pixel (b the
  // baseline, D the plane's distance from the camera centre), more than 1 px only for a plane
  // nearer than the baseline (0.11 m at EuRoC's rig: a floor under a camera 11 cm above it);
  // the refined disparities' noise is 0.1-0.4 px (dense_test). So a 1 px step between neighbours
  // is an edge or a mismatch. Measured (docs/benchmarks.md, "Dense depth: pixels beside depth edges
  // cleared"): on Middlebury's real aloe pair (opencv-doc, with its exact disparity, halved to 641
  // x 555) errors beyond 2 px 9.4 % -> 3.2 % of the pixels kept, at 80 % of them; on MH01_first10s
  // the pixels cleared disagree with the neighbouring keyframes' depth (by more than 1 px) more
  // than three times as often as those kept (61 % against 18 %); the hall loop's mesh 1.29 / 5.53
  // -> 1.23 / 4.85 cm at completeness 0.769 -> 0.766. Radius 1 / 3: hall 5.02 / 4.71 cm, MH01's
  // kept pixels 77 / 86 % consistent (82 % at 2), and a fifth more pixels cleared at 3 than at 2.
  double edge_jump = 1.0;
  int edge_radius = 2;

  void Visit(io::OptionVisitor& visitor);
  void Validate() const;  // throws std::invalid_argument
};

// Truncated signed distance fusion of keyframe depth (Open3D's scalable volume: blocks of
// voxels allocated where surfaces are, so memory grows with the surface, not the space).
struct FusionOptions {
  static constexpr char kSection[] = "dense_fusion";

  // Voxel edge [m]. 2 cm: the accuracy asked of the mesh (issue 33: median 2 cm), and a
  // quarter pixel of disparity at 2.5 m (the depth noise fusion averages away).
  double voxel_size = 0.02;
  // Truncation [m] of the signed distance, as voxels: 4 voxels span the depth noise up to about
  // 4 m (a quarter pixel there is 8 cm) without surfaces behind each other merging.
  double truncation = 0.08;
  // Voxels along a block's edge (Open3D's volume unit): 8 x 2 cm = 16 cm blocks, which the
  // band (8 cm either side of a surface) fills. Against 16 (32 cm) on MH01_first10s: fusion
  // 46.5 -> 28.4 ms a keyframe, volume 950 -> 584 MB; exact depth gives the same surface.
  int block_resolution = 8;
  // At most this many (a 64^3 block holds 262,144 voxels, far more than any band needs): the
  // fusion's voxel loop keeps a row of a block on the stack.
  static constexpr int kMaxBlockResolution = 64;
  // Standard deviation of a stereo disparity [px]: with the rig's focal length and baseline it
  // gives each depth's variance (sigma_z = noise * z^2 / (f * b)), whose inverse weighs the
  // measurement. 0.25 px: the rendered hall's median absolute disparity error before the
  // refinement, 0.14-0.18 px (dense_test), is 0.67 sigma of a normal distribution; so is the 90th
  // percentile's mean after the refinement, 0.42 px, 1.645 sigma. The smoothing lowered the
  // errors (90th percentile mean 0.32 px: 0.2 px by that rule) and 0.25 stays: a lower value
  // weighs far depths more and lets more of them through max_surface_sigma, a trade rather than a
  // gain (hall loop seed 1: 0.22 px gave mesh 1.49 / 6.28 cm, completeness 0.792, against 1.34 /
  // 5.59 cm, 0.766), and real pairs are noisier than rendered ones.
  double disparity_noise = 0.25;
  // A surface is taken out of the volume only where the fused signed distance's standard
  // deviation (1 / sqrt of the summed weights) is at most this [m]. What one far view or a
  // mismatch puts in front of or behind a wall is dropped until enough views agree. 8 cm, the
  // truncation band: a surface whose place is known within the band. On a lap of the rendered
  // hall at exact poses (dense_test, refined and smoothed disparities) vertices lie at a median
  // 1.3 cm / 90 % 4.0 cm from the exact surface and cover 61 % of what the lap measured within
  // reach; 3 cm gives 0.65 / 2.3 cm and 7.3 %, no limit 2.0 / 8.4 cm and 92 %. The errors stay
  // below those of a normal distribution of this deviation.
  double max_surface_sigma = 0.08;
  // Blocks are allocated only around depths whose standard deviation is at most this [m]
  // (5.7 m at EuRoC's rig); farther depths update the blocks nearer ones allocated. Twice the
  // band: a depth that uncertain places no surface inside the band it would allocate. On a lap
  // of the rendered hall: blocks 64,548 -> 50,307, the default mesh's accuracy 2.3 -> 2.2 cm
  // median and its coverage 0.54 -> 0.52 (the band itself, 8 cm: 19,495 blocks, coverage 0.45).
  double max_allocation_sigma = 0.16;
  // How far behind a measured surface a view still updates voxels, beyond the truncation band:
  // this many standard deviations of the depth (0: the band only). A voxel on the surface whose
  // view measured it behind (noise) gets -1 clamped, as one measured in front gets +1; with
  // nothing counted behind the band the fused distance of a surface seen only by depths whose
  // deviation exceeds the band (beyond 4 m at EuRoC's rig) is pulled behind it, the thin bands
  // outside the hall's far walls in the demo's picture. Measured on three hall routes (loop 34 s
  // seeds 1 and 3, figure eight 40 s seed 2; mesh median / 90 % [cm], completeness): 0 gives
  // 2.17 / 6.88, 0.769; 2.32 / 7.59, 0.755; 2.81 / 8.34, 0.700. 1 gives 1.92 / 8.63, 0.811;
  // 2.18 / 11.54, 0.800; 2.58 / 10.20, 0.775: more complete and a lower median, but more far-off
  // vertices (surfaces behind occluding edges that views now put in). 1 with max_surface_sigma
  // 0.06: 1.50 / 6.05, 0.742; 1.67 / 7.33, 0.725; 2.09 / 7.41, 0.683. Neither dominates the
  // default on every measure, so it stays 0 (docs/benchmarks.md).
  double behind_band_sigmas = 0.0;
  // How far in front of a measured surface a voxel beyond the band is left alone rather than
  // marked free: this many standard deviations of the depth (0: none, every voxel in front of
  // the band is free space). Where a depth's deviation exceeds the band (beyond 4 m at EuRoC's
  // rig) a voxel on the wall gets +1 from the depths measured behind it and nothing from those
  // in front beyond the band, so the fused wall lies behind the true one (10 cm at 5 m,
  // dense_test); leaving the voxels within two deviations in front alone as well balances the
  // two sides without writing behind the surface, which behind_band_sigmas does (into what
  // other views see behind occluding edges). Two deviations: a depth more than that behind the
  // voxel is rare (2.3 %), so a voxel that far in front is free space. On four hall routes
  // (mesh median / 90 % [cm], completeness; docs/benchmarks.md), 0 -> 2: loop seed 1 1.34 / 5.59,
  // 0.766 -> 1.29 / 5.53, 0.769; seed 3 1.52 / 6.93, 0.749 -> 1.50 / 6.93, 0.754; figure eight
  // 2.00 / 7.18, 0.704 -> 1.82 / 6.74, 0.716; four laps 2.29 / 10.84, 0.819 -> 1.99 / 10.39,
  // 0.844; 3 measured the same as 2 on seed 1.
  double front_uncertain_sigmas = 2.0;

  void Visit(io::OptionVisitor& visitor);
  void Validate() const;  // throws std::invalid_argument
};

// How the dense mapping stage (DenseMappingStage) schedules its work.
struct DenseMappingOptions {
  static constexpr char kSection[] = "dense_mapping";

  // Stereo pairs kept to find a keyframe's, and keyframes kept waiting for theirs: in the graph
  // the tracker publishes a keyframe after it has tracked its pair, at most its queue (a few
  // pairs) behind. 100 pairs are 5 s at EuRoC's 20 Hz, 72 MB at 752 x 480.
  int buffered_pairs = 100;
  // After a loop closes, every map update moves most keyframes a little: fused again all at once
  // they kept the DenseMapper minutes behind the new keyframes on the demo's loop. So each step
  // fuses the new keyframes first, then at most this many moved ones (those that moved most):
  // 4 is about a keyframe period's work beside the tracker (70-100 ms each on two cores).
  int moves_per_step = 4;

  void Visit(io::OptionVisitor& visitor);
  void Validate() const;  // throws std::invalid_argument
};

}  // namespace stereo_fabmap_slam::dense
