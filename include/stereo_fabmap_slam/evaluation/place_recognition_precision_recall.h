#pragma once

#include <limits>
#include <vector>

namespace stereo_fabmap_slam::evaluation {

// A place recognizer's answer to one query frame, judged against ground truth.
struct PlaceQueryResult {
  int query = 0;                // frame index
  bool has_candidates = false;  // some earlier frame lies outside the exclusion window
  bool has_true_match = false;  // ...and ground truth says one of them shows the same place
  int best_place = -1;          // the best candidate: a FAB-MAP place or an image; -1: none
  int best_frame = -1;          // a frame of that place (see PlaceRecognitionQueries)
  double score = 0;  // FAB-MAP log odds of best_place (FabMapResult), or its tf-idf cosine
  double new_place_probability = std::numeric_limits<double>::quiet_NaN();  // FAB-MAP only
  // FAB-MAP over the whole map, recent frames included: no place reached the match threshold,
  // so by appearance the view shows a new place (FabMap::Add then founds one; with odometry
  // poses it also founds one when only a place far away matched). False for methods without
  // the notion.
  bool declared_new = false;
  bool is_true = false;  // ground truth: the query shows the same place as best_frame
  // Where the first true answer stands in the method's ranking of the candidates (0 = best):
  // FAB-MAP's places with a posterior at or above the loop detector's floor, tf-idf's images by
  // cosine; -1 if none of the first kRankedCandidates is true. The loop detector verifies its
  // best few geometrically, so a true place among them can still close the loop.
  int true_candidate_rank = -1;
  static constexpr int kRankedCandidates = 10;
};

// Declaring a match whenever the score reaches `threshold`.
struct PlacePrecisionRecallPoint {
  double threshold = 0;
  int declared = 0;  // queries whose best candidate scores >= threshold
  int correct = 0;   // of those, the ones ground truth confirms
  double precision = 0;
  double recall = 0;  // correct / queries with a true match
};

// One point per distinct score, highest threshold first. Queries with equal scores are declared
// together: a threshold cannot separate them. Recall is 0 when no query has a true match.
std::vector<PlacePrecisionRecallPoint> PrecisionRecallCurve(
    const std::vector<PlaceQueryResult>& results);

// The highest recall of any point without a false match; 0 if even the top score is wrong.
double RecallAtFullPrecision(const std::vector<PlacePrecisionRecallPoint>& curve);

// Declaring a match wherever the score reaches `threshold`: how many, how many right, precision
// (1 when nothing is declared: no false match) and recall.
PlacePrecisionRecallPoint PointAtThreshold(const std::vector<PlaceQueryResult>& results,
                                           double threshold);

// Area under the precision-recall curve as the step function the sweep traces (average
// precision: sum of precision x recall gained at each threshold; no interpolation, which would
// credit a method with precision it never reaches at that recall).
double AreaUnderCurve(const std::vector<PlacePrecisionRecallPoint>& curve);

// Candidate recall @K: of the queries with a true match, the fraction whose true answer is among
// the method's K best candidates (true_candidate_rank < K); 0 without such queries. K must lie
// in [1, PlaceQueryResult::kRankedCandidates].
double CandidateRecall(const std::vector<PlaceQueryResult>& results, int k);

struct PlaceRecognitionSummary {
  int queries = 0;                  // frames with at least one loop candidate
  int queries_with_true_match = 0;  // of those, with a true earlier match outside the window
  int declared_new = 0;             // FAB-MAP: frames the whole map would call a new place
  double recall_at_full_precision = 0;
  double auc = 0;
  double candidate_recall_at_1 = 0, candidate_recall_at_3 = 0, candidate_recall_at_5 = 0;
};

PlaceRecognitionSummary SummarizePlaceRecognition(const std::vector<PlaceQueryResult>& results);

}  // namespace stereo_fabmap_slam::evaluation
