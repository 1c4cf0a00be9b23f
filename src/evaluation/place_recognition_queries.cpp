#include "stereo_fabmap_slam/evaluation/place_recognition_queries.h"

#include <stdexcept>
#include <string>

namespace stereo_fabmap_slam::evaluation {
namespace {

void CheckSizes(const PlaceRecognitionFrames& frames, const PlaceGroundTruth& truth) {
  const std::size_t n = frames.times.size();
  if (frames.words.size() != n || frames.word_sets.size() != n ||
      truth.size() != static_cast<int>(n)) {
    throw std::invalid_argument("place recognition queries: " + std::to_string(n) +
                                " frames, but " + std::to_string(frames.words.size()) +
                                " word lists, " + std::to_string(frames.word_sets.size()) +
                                " word sets and a ground truth of " + std::to_string(truth.size()));
  }
}

// What every method's result shares: whether the query can have a loop, and has a true one.
PlaceQueryResult NewResult(const PlaceRecognitionFrames& frames, const PlaceGroundTruth& truth,
                           int query) {
  PlaceQueryResult result;
  result.query = query;
  for (int i = 0; i < query; ++i) {
    if (!frames.IsCandidate(i, query)) continue;
    result.has_candidates = true;
    if (truth.Same(i, query)) {
      result.has_true_match = true;
      break;
    }
  }
  return result;
}

}  // namespace

const char* PlacesModeName(PlacesMode mode) {
  return mode == PlacesMode::kPerImage ? "per-image" : "update";
}

ExcludedPairs CountExcludedPairs(const PlaceRecognitionFrames& frames,
                                 const PlaceGroundTruth& truth) {
  ExcludedPairs excluded;
  for (int j = 0; j < frames.size(); ++j) {
    for (int i = j - 1; i >= 0 && !frames.IsCandidate(i, j); --i) {
      ++excluded.pairs;
      excluded.same_place += truth.Same(i, j) ? 1 : 0;
    }
  }
  return excluded;
}

std::vector<PlaceQueryResult> RunFabMapQueries(const PlaceRecognitionFrames& frames,
                                               const PlaceGroundTruth& truth, PlacesMode mode,
                                               double match_log_odds,
                                               place_recognition::FabMap* fabmap,
                                               const QueryProgress& progress) {
  CheckSizes(frames, truth);
  if (fabmap->places().size() != 0) throw std::invalid_argument("RunFabMapQueries: a used map");
  std::vector<std::vector<int>> members;  // per place: its frames, in time order
  std::vector<PlaceQueryResult> results;
  for (int j = 0; j < frames.size(); ++j) {
    PlaceQueryResult result = NewResult(frames, truth, j);
    const std::vector<int>& words = frames.word_sets[static_cast<std::size_t>(j)];
    // Frames are in time order, so a place's first frame is its oldest.
    std::vector<char> candidates(members.size());
    for (std::size_t p = 0; p < members.size(); ++p)
      candidates[p] = frames.IsCandidate(members[p].front(), j) ? 1 : 0;
    if (result.has_candidates) {
      const place_recognition::FabMapResult restricted = fabmap->Compare(words, candidates);
      result.new_place_probability = restricted.new_place;
      if (restricted.best >= 0) {
        result.best_place = restricted.best;
        result.score = restricted.best_log_odds;
        for (const int frame : members[static_cast<std::size_t>(restricted.best)]) {
          if (!frames.IsCandidate(frame, j)) break;
          result.best_frame = frame;
          if (truth.Same(frame, j)) {
            result.is_true = true;
            break;
          }
        }
      }
    }
    if (mode == PlacesMode::kUpdate) {
      int place = -1;
      fabmap->Add(words, &place);
      result.declared_new = place == static_cast<int>(members.size());
      if (result.declared_new) members.emplace_back();
      members[static_cast<std::size_t>(place)].push_back(j);
    } else {
      if (!members.empty()) {
        const place_recognition::FabMapResult full = fabmap->Compare(words);
        result.declared_new = full.best_log_odds < match_log_odds;
      } else {
        result.declared_new = true;
      }
      fabmap->AddPlace(words);
      members.push_back({j});
    }
    results.push_back(result);
    if (progress) progress(j + 1, frames.size());
  }
  return results;
}

std::vector<PlaceQueryResult> RunTfIdfQueries(const PlaceRecognitionFrames& frames,
                                              const PlaceGroundTruth& truth,
                                              place_recognition::TfIdfIndex* index) {
  CheckSizes(frames, truth);
  if (index->size() != 0) throw std::invalid_argument("RunTfIdfQueries: a used index");
  std::vector<PlaceQueryResult> results;
  for (int j = 0; j < frames.size(); ++j) {
    PlaceQueryResult result = NewResult(frames, truth, j);
    const std::vector<int>& words = frames.words[static_cast<std::size_t>(j)];
    if (result.has_candidates) {
      const std::vector<double> scores = index->Score(words);
      for (int i = 0; i < j && frames.IsCandidate(i, j); ++i) {
        if (result.best_place < 0 || scores[static_cast<std::size_t>(i)] > result.score) {
          result.best_place = i;
          result.score = scores[static_cast<std::size_t>(i)];
        }
      }
      result.best_frame = result.best_place;
      result.is_true = result.best_place >= 0 && truth.Same(result.best_place, j);
    }
    index->Add(words);
    results.push_back(result);
  }
  return results;
}

}  // namespace stereo_fabmap_slam::evaluation
