#pragma once

#include <limits>
#include <string>

#include "stereo_fabmap_slam/features/features_options.h"
#include "stereo_fabmap_slam/geometry/pnp_ransac.h"
#include "stereo_fabmap_slam/io/option_reader.h"

namespace stereo_fabmap_slam::place_recognition {

struct VocabularyOptions {
  static constexpr char kSection[] = "vocabulary";

  int branching = 10;  // children per node
  int depth = 4;       // levels: up to branching^depth words (10,000 by default)
  int iterations = 8;  // clustering iterations per node
  int seed = 1;

  void Visit(io::OptionVisitor& visitor);
  void Validate() const;  // throws std::invalid_argument
};

// p(Z | new place): the mean-field approximation, or an average over sampled training places.
enum class NewPlaceModel { kMeanField, kSampling };
// Where the detector model comes from: estimated by train_fabmap from its training sequences
// (detector_model.yaml beside the vocabulary), or the two fixed values of the options.
enum class DetectorModelSource { kTrained, kFixed };
// The prior over places: uniform, or favouring the neighbours of the last match.
enum class LocationPrior { kUniform, kMotion };

// Throws std::invalid_argument "<what>: need 0 <= p_z_given_not_e < p_z_given_e < 1" unless so.
void ValidateDetectorRates(double p_z_given_e, double p_z_given_not_e, const std::string& what);

struct FabMapOptions {
  static constexpr char kSection[] = "fabmap";

  // trained: p(z|e) and p(z|not e) from the vocabulary's detector_model.yaml, what its training
  // views showed (ResolveDetectorModel fills the two fields below); fixed: the two fields.
  DetectorModelSource detector_model = DetectorModelSource::kTrained;
  double p_z_given_e = 0.39;  // detector model: p(word seen | scene element present)
  // p(word seen | element absent): false detections. Never 0: a place seen n times without a
  // word would then rule it out for good (its p(e) falls as 1.6^-n), and one noisy detection in
  // an unchanged view made a hovering camera's place a new one. Cummins & Newman's 0 assumed
  // a detector without false positives; quantised corners have them.
  double p_z_given_not_e = 0.005;
  double new_place_prior = 0.9;  // prior that a view shows a place not in the map
  double smoothing = 0.99;       // posterior smoothing: p -> s p + (1 - s) / (places + 1)
  NewPlaceModel new_place_model = NewPlaceModel::kMeanField;  // mean_field, or sampling
  LocationPrior location_prior = LocationPrior::kUniform;     // uniform, or motion
  double motion_weight = 0.6;  // motion prior: share of the existing-place mass on neighbours
  bool inverted_index = true;  // FAB-MAP 2.0 (inverted index); false: FAB-MAP 1.0 (every word)
  // FAB-MAP 2.0 only. false: a word absent from the view is scored as if its Chow-Liu parent
  // were absent too, so that only the view's own words are looked up (half the index reads;
  // it finds the same best place as FAB-MAP 1.0, see the tests). true: also correct the absent
  // children of the view's words, giving FAB-MAP 1.0's log-likelihoods (to the single precision
  // in which 2.0 sums each place's corrections: within 1e-6 of the value) and ranking.
  bool exact_tree_corrections = false;
  // A view shows its best place when FabMapResult::best_log_odds reaches this, i.e. when that
  // place is at least e^match_log_odds times likelier than a new one: Add() then updates it,
  // otherwise adds a new place; evaluate_place_recognition reports precision and recall here.
  // 0, "the likelier of the two", is the decision FAB-MAP's model itself makes, with no margin
  // tuned to a sequence. (A threshold on the smoothed posterior cannot serve: it saturates.)
  double match_log_odds = 0;
  // Add(): a view updates its best place only if it would also match the place's first view
  // alone. A place then stays around where it was first seen, instead of growing along a chain
  // of similar views down a corridor into one place for the whole corridor.
  bool update_near_first_view = false;
  // Add() with the odometry's position of the view: a view updates only a place founded in the
  // same odometry segment at most this far from it. Appearance alone lets a place grow down a
  // corridor of identical doors and across look-alike corridors, views metres apart that no
  // word tells apart; the odometry does. 1 m: views from within a metre share most of what
  // they see at indoor depths (2-5 m), so a place stays one location (the loop detector's
  // max_loop_distance, 0.8 m, is the same notion); and stereo odometry drifts about 1 % of the
  // path, 0.5 m over a 50 m lap, so a revisit after a lap of a room or a floor still updates
  // the place it saw. Not a speed or frame-rate figure: the place spans at most 2 m of path per
  // pass, whatever the camera does. inf: no limit.
  double max_place_extent = 1.0;  // [m]
  // ...and whose optical axis is within this angle of the place's first view's. A camera that
  // turns on the spot sees another scene: 20 deg keeps three quarters of a 80 deg wide view
  // (EuRoC's), so a place spans at most a 40 deg fan, short of the half image (tau 0.5) that
  // makes two views one place in the ground truth. 180: no limit.
  double max_place_turn_deg = 20;

  void Visit(io::OptionVisitor& visitor);
  void Validate() const;  // throws std::invalid_argument
};

struct TrainingOptions {
  static constexpr char kSection[] = "training";

  int spacing = 10;  // train_fabmap: every N-th frame of a sequence, so that views are distinct

  void Visit(io::OptionVisitor& visitor) { visitor.Visit("spacing", &spacing); }
  void Validate() const;  // throws std::invalid_argument
};

// Loop detection in the running system: which keyframes FAB-MAP may propose, and how a proposal
// is verified. The thresholds are for precision first: one false loop wrecks a map, a missed
// one only leaves drift until the next revisit.
struct LoopDetectorOptions {
  static constexpr char kSection[] = "loop_detection";

  // Keyframes younger than this (relative to the query) are not places to return to: the
  // odometry already connects them. 10 s is several keyframes at walking or flying speed and
  // far shorter than any lap worth closing.
  double min_age = 10.0;  // [s]
  // FAB-MAP candidates: the best few whose posterior reaches min_probability. Consecutive
  // keyframes of one old place share the posterior mass, so a true revisit often shows as
  // several candidates of 0.1 - 0.5 each; verification, not this threshold, gives precision.
  // Used only without a sequence (sequence_length 1): one view's posterior.
  double min_probability = 0.05;
  // ...and whose log odds against a new place (FabMapResult::CandidateLogOdds, or the sequence
  // score) reach this. 0: likelier a revisit than new places, FAB-MAP's own decision, no margin
  // tuned to a sequence; it spares verifying candidates where nothing matched.
  double min_log_odds = 0;
  int max_candidates = 3;
  // Temporal consistency (SequenceScore): candidates are ranked by the summed log odds along
  // the best chain of the last sequence_length keyframes of the query's odometry segment over
  // neighbouring keyframes (at most sequence_max_step apart per keyframe); min_log_odds applies
  // to that sum, and min_probability, one view's posterior, does not: the chain is what picks
  // the place out of look-alikes a single view cannot tell apart (identical doors, a poster
  // hung on several walls). 5 keyframes, about 1.25 m of path at keyframes.max_translation
  // 0.25 m: from 3 on, one look-alike view cannot outweigh a run; longer chains also add up
  // runs of near-duplicate views (a hovering camera) and corridors that look alike for metres,
  // and take longer to form after a route rejoins an old one. Not the best length on any one
  // sequence measured (docs/place_recognition.md: 8 ranks the office better, 3 MH01). A step
  // of 3 keyframes outruns any walking or flying revisit.
  int sequence_length = 5;
  int sequence_max_step = 3;
  // Geometric verification: query key points matched by descriptor to the candidate's stereo
  // points (nearest / second nearest < match_ratio), PnP RANSAC, motion-only refinement.
  double match_ratio = 0.8;
  geometry::PnpKernel pnp_kernel = geometry::PnpKernel::kAp3p;
  double ransac_threshold = 2.0;  // [px]
  int ransac_iterations = 300;    // no motion prior: inlier ratios can be low
  // Accept only with this many inliers after refinement (the tracker calls 50 good tracking)...
  int min_inliers = 40;
  // ...spread over at least this many cells of a 4 x 4 grid over the image, so that a single
  // textured object (a poster repeated elsewhere in the building) cannot verify a loop alone.
  int min_inlier_cells = 6;
  // Within one odometry segment the verified relative pose must agree with the odometry's up to
  // the drift the odometry can have gathered between the two keyframes: max_drift_fraction of
  // the path travelled between them, and never less than min_drift_allowance. Stereo odometry
  // drifts ~1 % of the distance; 5 % leaves a wide margin yet rejects a look-alike place metres
  // away after a short path.
  double max_drift_fraction = 0.05;
  double min_drift_allowance = 0.3;    // [m]
  double max_rotation_drift_deg = 10;  // [deg] heading the odometry cannot have lost
  // Across odometry segments the same holds through the last loop accepted for the query's
  // segment, while the query has gone at most loop_consistency_path since it: the candidate must
  // sit where that loop and both segments' odometry put it (the same allowances, over both
  // paths). A revisit is a run of loops that agree; a door of another corridor that passes
  // verification inside such a run (on a per-seed office loop, 13 m from the truth between
  // loops to the right corridor) does not. 3 m: a run of loops on a corridor walked again spans
  // metres, and a wrong loop taken as the reference (one that opened a run) blocks the true
  // ones for no longer than that.
  double loop_consistency_path = 3.0;  // [m]
  // Only loops between nearby views: the farther apart two cameras are, the less near
  // structure they share and the worse PnP measures their relative pose. Keyframes are at most
  // 0.25 m apart along the path (keyframes.max_translation), so a true revisit passes within
  // about 0.15 m of an old keyframe; 0.8 m leaves room for a path some decimetres off the old
  // one, and a farther candidate is no loss: a nearer keyframe of the same place follows.
  double max_loop_distance = 0.8;  // [m] verified distance between the two cameras
  // Uncertainty of a verified relative pose for the pose graph: PnP + refinement on >= 40 stereo
  // inliers at indoor depths is good to about a centimetre and a tenth of a degree; twice that.
  double translation_sigma = 0.02;  // [m]
  double rotation_sigma_deg = 0.2;  // [deg]

  void Visit(io::OptionVisitor& visitor);
  void Validate() const;  // throws std::invalid_argument
};

// Everything place recognition is configured with (config/fabmap.yaml).
struct PlaceRecognitionOptions {
  // Folder with vocabulary.bin, chow_liu_tree.bin and training_places.bin (train_fabmap); a
  // relative path is relative to the configuration file.
  std::string vocabulary_directory;
  // The odometry's detector and descriptor, with a selection (how many corners, ANMS or the
  // strongest) of its own: config/fabmap.yaml says which and why.
  features::FeatureOptions features;
  VocabularyOptions vocabulary;
  FabMapOptions fabmap;
  TrainingOptions training;

  void Validate() const;
};

// Reads config/fabmap.yaml. `odometry_features` supplies what the file's "features" section does
// not set (detector, descriptor, thresholds). Unknown keys and bad values throw io::InputError.
PlaceRecognitionOptions LoadPlaceRecognitionOptions(
    const std::string& path, const features::FeatureOptions& odometry_features);

}  // namespace stereo_fabmap_slam::place_recognition
