#pragma once

#include "stereo_fabmap_slam/geometry/pnp_ransac.h"
#include "stereo_fabmap_slam/io/option_reader.h"

namespace stereo_fabmap_slam::relocalization {

// Finding a frame in the keyframe map with no idea where it is: FAB-MAP proposes keyframes, and
// each is verified against its own and its neighbours' stereo points. There is no odometry to
// cross-check a relocalization (that is the point of it), so the thresholds are stricter than
// loop detection's: a wrong relocalization puts the camera in the wrong place of the map.
struct RelocalizerOptions {
  static constexpr char kSection[] = "relocalization";

  // FAB-MAP's best keyframes, whatever their posterior: a lost camera has no prior, and after a
  // kidnap the view may be new to FAB-MAP (posterior spread over several similar places) yet
  // verify well. Each costs a few milliseconds of matching and RANSAC; 5 bounds an attempt.
  int max_candidates = 5;
  // The candidate's neighbours on its odometry segment (this many either side) lend their
  // points to the guided search: a view between two keyframes shares more with the pair than
  // with either. Descriptor matching uses the candidate's own points only: matching against
  // five keyframes' points cost a fifth more per attempt and found no more views (rendered
  // kidnap and figure8 routes, MH01).
  int neighbours = 2;
  // Descriptor matching (nearest / second nearest < match_ratio), PnP RANSAC, refinement.
  double match_ratio = 0.8;
  geometry::PnpKernel pnp_kernel = geometry::PnpKernel::kAp3p;
  double ransac_threshold = 2.0;  // [px]
  int ransac_iterations = 300;    // no motion prior: inlier ratios can be low
  // RANSAC's consensus (and the descriptor matches it needs) to seed the guided search; a view
  // seen from a few decimetres off the keyframe matches only part of its points by descriptor.
  int min_ransac_inliers = 20;
  // Guided search: every point of the candidate and its neighbours projected with the refined
  // pose finds its best key point within this radius (descriptor limit and ratio as above).
  // A pose from >= 20 inliers is good to a pixel or two; 8 px leaves room for its error.
  double search_radius = 8.0;  // [px]
  // Acceptance after the guided search: the tracker's own "tracking ok" level (50 inliers), as
  // a relocalized frame is tracked from at once...
  int min_inliers = 50;
  // ...spread over this many cells of a 4 x 4 grid, so that one textured object repeated
  // elsewhere (a poster, a sign) cannot place the camera alone. Loop detection asks for 6 and has
  // the odometry as a second check; without it, 8 cells: half the image.
  int min_inlier_cells = 8;
  // Automatic recovery after tracking loss: attempt on every n-th frame while lost. An attempt
  // costs 6-9 ms in the hall, where the first candidate passes, but 34-40 ms median in the
  // office, where look-alike candidates fail one after another: on the per-seed office routes,
  // whose segments stay unjoined for long, attempts on every frame were a quarter to a third of
  // run_dataset's time. 4 (0.2 s at 20 Hz, 0.2 m at 1 m/s) delays a join by no more than that,
  // while a confirmation needs confirm_distance (1.5 m) of travel anyway, and the segment's
  // keyframes look for loops at every keyframe meanwhile.
  int attempt_every_n_frames = 4;
  // Mapping, after a loss: the first success is a candidate; a second one from a camera at
  // least confirm_distance (straight line, in the new segment's odometry) from where the
  // candidate was found must put the camera where the first one's map -> odom does before a
  // relocalization edge joins the segment to the map (one that disagrees becomes the
  // candidate). One view cannot tell identical corridors apart:
  // their doors and lights verify a pose metres off with 150+ inliers spread over the whole
  // image (docs/place_recognition.md), and a view half a metre on, still of doors and lights,
  // agrees with it. Further on the view holds what tells corridors apart (a poster, a notice
  // board, the corridor's end): buildings space such things a few metres apart. 1.5 m: longer
  // than the loop detector's chain of keyframes (5 x 0.25 m), which keeps loops right the same
  // way where no loss broke the odometry. A kidnapped camera is not kept waiting: the loop
  // detector joins its segment as soon as a keyframe of it verifies. 0: the first success joins.
  double confirm_distance = 1.5;  // [m]
  // Agreement: the two relocalizations each good to a centimetre or two (translation_sigma);
  // these bounds leave room for that and for the pose graph moving the map between the two,
  // and lie far below the spacing of a building's repeated doors and lights (metres).
  double confirm_translation = 0.15;  // [m]
  double confirm_rotation_deg = 2;    // [deg]
  // Uncertainty of a relocalization edge in the pose graph: as a verified loop's.
  double translation_sigma = 0.02;  // [m]
  double rotation_sigma_deg = 0.2;  // [deg]

  void Visit(io::OptionVisitor& visitor);
  void Validate() const;  // throws std::invalid_argument
};

}  // namespace stereo_fabmap_slam::relocalization
