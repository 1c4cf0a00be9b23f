#pragma once

#include <functional>
#include <limits>
#include <vector>

#include "stereo_fabmap_slam/evaluation/place_ground_truth.h"
#include "stereo_fabmap_slam/evaluation/place_recognition_precision_recall.h"
#include "stereo_fabmap_slam/place_recognition/fab_map.h"
#include "stereo_fabmap_slam/place_recognition/sequence_score.h"
#include "stereo_fabmap_slam/place_recognition/tf_idf_index.h"

namespace stereo_fabmap_slam::evaluation {

// The frames of one sequence as place recognition sees them, in time order.
struct PlaceRecognitionFrames {
  std::vector<std::vector<int>> words;      // per frame: one word per feature (tf-idf)
  std::vector<std::vector<int>> word_sets;  // per frame: its sorted distinct words (FAB-MAP)
  std::vector<double> times;                // per frame, non-decreasing: [s] or frame numbers
  // Earlier frames no more than `window` before a query (same unit as times) are its recent
  // past, which odometry connects anyway: neither loop candidates nor true loops.
  double window = 0;
  // Per frame, where the odometry put its camera, or empty: no odometry (an image folder).
  // Updated places then spread no farther than fabmap.max_place_extent and
  // max_place_turn_deg from where they were founded (FabMap::Add with a pose).
  std::vector<place_recognition::ViewPose> odometry_poses;

  int size() const { return static_cast<int>(times.size()); }
  bool IsCandidate(int earlier, int query) const {
    return earlier < query && times[query] - times[earlier] > window;
  }
};

// FAB-MAP's places: one per image (every image becomes a place of its own, as the SLAM map keeps
// one per keyframe), or updated on revisits (FabMap::Add: the best place takes the view when
// its log odds reach match_log_odds, otherwise the view becomes a new place; with the frames'
// odometry poses, only a place founded near the view may take it).
enum class PlacesMode { kPerImage, kUpdate };
const char* PlacesModeName(PlacesMode mode);  // "per-image", "update"

struct ExcludedPairs {
  long pairs = 0;       // pairs (earlier, query) inside the window
  long same_place = 0;  // of those, pairs ground truth calls the same place
};
ExcludedPairs CountExcludedPairs(const PlaceRecognitionFrames& frames,
                                 const PlaceGroundTruth& truth);

using QueryProgress = std::function<void(int done, int total)>;

struct FabMapQueryOptions {
  PlacesMode mode = PlacesMode::kPerImage;
  double match_log_odds = 0;  // FabMap::Add's threshold (fabmap.match_log_odds)
  // The loop detector's posterior floor (loop_detection.min_probability): candidate ranks count
  // only places at or above it, as the detector hands only those to geometric verification.
  double candidate_floor = 0;
  // ...and its floor on a candidate's log odds against a new place (loop_detection.min_log_odds).
  double candidate_min_log_odds = -std::numeric_limits<double>::infinity();
  // Temporal consistency: with a length above 1, places are ranked by their sequence score
  // (place_recognition::SequenceScore over the queries in time order), the score and
  // candidate_min_log_odds apply to it, and the posterior floor, a single view's, is not used.
  place_recognition::SequenceScoreOptions sequence;
};

struct FabMapQueries {
  std::vector<PlaceQueryResult> results;  // per frame
  std::vector<int> place_of_frame;        // the place each frame became or joined
};

// How the frames fell into places. A location is revisited when a frame has a true match
// outside the window; the frames showing it are that frame and every frame ground truth calls
// the same place. One place per location is the ideal; one place for many locations (a corridor
// swallowed whole) is what the largest place's share reveals.
struct PlaceMapShape {
  int places = 0;
  int largest_place_frames = 0;
  double largest_place_share = 0;            // of all frames
  int revisited_locations = 0;               // frames with a true match outside the window
  double places_per_revisited_location = 0;  // mean distinct places among a location's frames
};
PlaceMapShape DescribePlaces(const PlaceRecognitionFrames& frames, const PlaceGroundTruth& truth,
                             const std::vector<int>& place_of_frame);

// Each frame in turn is a query against the places built from the frames before it; then it
// joins the map as `options.mode` says. The query is compared with the places that hold a frame
// outside the window (FabMap::Compare over candidates, as loop detection leaves out the recent
// past): the best of them, its posterior and the new-place probability. A place is the query's true
// match when ground truth links the query to one of the place's frames outside the window;
// best_frame is that frame, or the place's latest frame outside the window if none is.
// declared_new comes from the comparison with the whole map, recent frames included: Add's
// decision by appearance. `fabmap` must be empty; it holds the places afterwards. Throws
// std::invalid_argument if the frames and the ground truth differ in size.
FabMapQueries RunFabMapQueries(const PlaceRecognitionFrames& frames, const PlaceGroundTruth& truth,
                               const FabMapQueryOptions& options, place_recognition::FabMap* fabmap,
                               const QueryProgress& progress = nullptr);

// The same queries with the tf-idf cosine, one place per image: the best-scoring earlier image
// outside the window. `index` must be empty; it holds every frame afterwards.
std::vector<PlaceQueryResult> RunTfIdfQueries(const PlaceRecognitionFrames& frames,
                                              const PlaceGroundTruth& truth,
                                              place_recognition::TfIdfIndex* index);

}  // namespace stereo_fabmap_slam::evaluation
