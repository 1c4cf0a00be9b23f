#include "stereo_fabmap_slam/evaluation/place_recognition_precision_recall.h"

#include <algorithm>
#include <stdexcept>
#include <string>

namespace stereo_fabmap_slam::evaluation {

std::vector<PlacePrecisionRecallPoint> PrecisionRecallCurve(
    const std::vector<PlaceQueryResult>& results) {
  std::vector<const PlaceQueryResult*> answered;
  int with_true_match = 0;
  for (const PlaceQueryResult& result : results) {
    with_true_match += result.has_true_match ? 1 : 0;
    if (result.best_place >= 0) answered.push_back(&result);
  }
  std::sort(
      answered.begin(), answered.end(),
      [](const PlaceQueryResult* a, const PlaceQueryResult* b) { return a->score > b->score; });
  std::vector<PlacePrecisionRecallPoint> curve;
  PlacePrecisionRecallPoint point;
  for (std::size_t i = 0; i < answered.size(); ++i) {
    ++point.declared;
    point.correct += answered[i]->is_true ? 1 : 0;
    if (i + 1 < answered.size() && answered[i + 1]->score == answered[i]->score) continue;
    point.threshold = answered[i]->score;
    point.precision = static_cast<double>(point.correct) / point.declared;
    point.recall = with_true_match > 0 ? static_cast<double>(point.correct) / with_true_match : 0.0;
    curve.push_back(point);
  }
  return curve;
}

double RecallAtFullPrecision(const std::vector<PlacePrecisionRecallPoint>& curve) {
  double recall = 0;
  for (const PlacePrecisionRecallPoint& point : curve) {
    if (point.correct != point.declared) break;  // declared only grows: no later point is clean
    recall = point.recall;
  }
  return recall;
}

double AreaUnderCurve(const std::vector<PlacePrecisionRecallPoint>& curve) {
  double area = 0, previous_recall = 0;
  for (const PlacePrecisionRecallPoint& point : curve) {
    area += (point.recall - previous_recall) * point.precision;
    previous_recall = point.recall;
  }
  return area;
}

PlacePrecisionRecallPoint PointAtThreshold(const std::vector<PlaceQueryResult>& results,
                                           double threshold) {
  PlacePrecisionRecallPoint point;
  point.threshold = threshold;
  int with_true_match = 0;
  for (const PlaceQueryResult& result : results) {
    with_true_match += result.has_true_match ? 1 : 0;
    if (result.best_place < 0 || !(result.score >= threshold)) continue;
    ++point.declared;
    point.correct += result.is_true ? 1 : 0;
  }
  point.precision = point.declared > 0 ? static_cast<double>(point.correct) / point.declared : 1.0;
  point.recall = with_true_match > 0 ? static_cast<double>(point.correct) / with_true_match : 0.0;
  return point;
}

double CandidateRecall(const std::vector<PlaceQueryResult>& results, int k) {
  if (k < 1 || k > PlaceQueryResult::kRankedCandidates) {
    throw std::invalid_argument("candidate recall: K must lie in [1, " +
                                std::to_string(PlaceQueryResult::kRankedCandidates) + "]");
  }
  int with_true_match = 0, found = 0;
  for (const PlaceQueryResult& result : results) {
    if (!result.has_true_match) continue;
    ++with_true_match;
    found += result.true_candidate_rank >= 0 && result.true_candidate_rank < k ? 1 : 0;
  }
  return with_true_match > 0 ? static_cast<double>(found) / with_true_match : 0.0;
}

PlaceRecognitionSummary SummarizePlaceRecognition(const std::vector<PlaceQueryResult>& results) {
  PlaceRecognitionSummary summary;
  for (const PlaceQueryResult& result : results) {
    summary.queries += result.has_candidates ? 1 : 0;
    summary.queries_with_true_match += result.has_true_match ? 1 : 0;
    summary.declared_new += result.declared_new ? 1 : 0;
  }
  const std::vector<PlacePrecisionRecallPoint> curve = PrecisionRecallCurve(results);
  summary.recall_at_full_precision = RecallAtFullPrecision(curve);
  summary.auc = AreaUnderCurve(curve);
  summary.candidate_recall_at_1 = CandidateRecall(results, 1);
  summary.candidate_recall_at_3 = CandidateRecall(results, 3);
  summary.candidate_recall_at_5 = CandidateRecall(results, 5);
  return summary;
}

}  // namespace stereo_fabmap_slam::evaluation
