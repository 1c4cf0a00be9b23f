#include "stereo_fabmap_slam/evaluation/place_recognition_queries.h"

#include <algorithm>
#include <functional>
#include <limits>
#include <set>
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
  if (!frames.odometry_poses.empty() && frames.odometry_poses.size() != n) {
    throw std::invalid_argument("place recognition queries: " + std::to_string(n) +
                                " frames, but " + std::to_string(frames.odometry_poses.size()) +
                                " odometry poses");
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

// The first of the best-ranked candidates (`scores` over `count` candidates, `is_candidate`
// and `is_true` by index) that is true: its rank, or -1 beyond kRankedCandidates. Equal scores
// rank in index order, as the loop detector orders them.
int TrueCandidateRank(int count, const std::function<double(int)>& score,
                      const std::function<bool(int)>& is_candidate,
                      const std::function<bool(int)>& is_true) {
  std::vector<int> ranked;
  for (int i = 0; i < count; ++i) {
    if (is_candidate(i)) ranked.push_back(i);
  }
  const auto better = [&](int a, int b) {
    return score(a) > score(b) || (score(a) == score(b) && a < b);
  };
  const std::size_t kept =
      std::min<std::size_t>(ranked.size(), PlaceQueryResult::kRankedCandidates);
  std::partial_sort(ranked.begin(), ranked.begin() + static_cast<std::ptrdiff_t>(kept),
                    ranked.end(), better);
  for (std::size_t r = 0; r < kept; ++r) {
    if (is_true(ranked[r])) return static_cast<int>(r);
  }
  return -1;
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

FabMapQueries RunFabMapQueries(const PlaceRecognitionFrames& frames, const PlaceGroundTruth& truth,
                               const FabMapQueryOptions& options, place_recognition::FabMap* fabmap,
                               const QueryProgress& progress) {
  CheckSizes(frames, truth);
  if (fabmap->places().size() != 0) throw std::invalid_argument("RunFabMapQueries: a used map");
  std::vector<std::vector<int>> members;  // per place: its frames, in time order
  FabMapQueries run;
  std::vector<PlaceQueryResult>& results = run.results;
  place_recognition::SequenceScore sequence(options.sequence);
  for (int j = 0; j < frames.size(); ++j) {
    PlaceQueryResult result = NewResult(frames, truth, j);
    const std::vector<int>& words = frames.word_sets[static_cast<std::size_t>(j)];
    // Frames are in time order, so a place's first frame is its oldest.
    std::vector<char> candidates(members.size());
    for (std::size_t p = 0; p < members.size(); ++p)
      candidates[p] = frames.IsCandidate(members[p].front(), j) ? 1 : 0;
    // Each place's log odds against a new place (-infinity: no candidate), and what ranks
    // them: the log odds themselves, or their sequence score.
    std::vector<double> log_odds(members.size(), -std::numeric_limits<double>::infinity());
    place_recognition::FabMapResult restricted;
    if (result.has_candidates) {
      restricted = fabmap->Compare(words, candidates);
      for (std::size_t p = 0; p < members.size(); ++p) {
        if (candidates[p]) log_odds[p] = restricted.CandidateLogOdds(static_cast<int>(p));
      }
    }
    const bool by_sequence = options.sequence.length > 1;
    const std::vector<double> ranking = by_sequence ? sequence.Push(log_odds) : log_odds;
    if (result.has_candidates) {
      result.new_place_probability = restricted.new_place;
      // A place is a true answer when one of its frames outside the window shows the query's
      // place (frames are in time order: those outside the window come first).
      const auto place_is_true = [&](int place) {
        for (const int frame : members[static_cast<std::size_t>(place)]) {
          if (!frames.IsCandidate(frame, j)) break;
          if (truth.Same(frame, j)) return true;
        }
        return false;
      };
      if (result.has_true_match) {
        result.true_candidate_rank = TrueCandidateRank(
            static_cast<int>(members.size()),
            [&](int p) { return ranking[static_cast<std::size_t>(p)]; },
            [&](int p) {
              const auto i = static_cast<std::size_t>(p);
              return candidates[i] &&
                     (by_sequence || restricted.posterior[i] >= options.candidate_floor) &&
                     ranking[i] >= options.candidate_min_log_odds;
            },
            place_is_true);
      }
      int best = -1;
      for (std::size_t p = 0; p < members.size(); ++p) {
        if (candidates[p] && (best < 0 || ranking[p] > ranking[static_cast<std::size_t>(best)]))
          best = static_cast<int>(p);
      }
      if (best >= 0) {
        result.best_place = best;
        result.score = ranking[static_cast<std::size_t>(best)];
        for (const int frame : members[static_cast<std::size_t>(best)]) {
          if (!frames.IsCandidate(frame, j)) break;
          result.best_frame = frame;
          if (truth.Same(frame, j)) {
            result.is_true = true;
            break;
          }
        }
      }
    }
    if (options.mode == PlacesMode::kUpdate) {
      int place = -1;
      const place_recognition::FabMapResult full =
          frames.odometry_poses.empty()
              ? fabmap->Add(words, &place)
              : fabmap->Add(words, frames.odometry_poses[static_cast<std::size_t>(j)], &place);
      // Declared by appearance over the whole map, as with one place per image; which place
      // takes the view is the map's business (with odometry, a look-alike place far away does
      // not, and the view founds one of its own).
      result.declared_new = full.best < 0 || full.best_log_odds < options.match_log_odds;
      if (place == static_cast<int>(members.size())) members.emplace_back();
      members[static_cast<std::size_t>(place)].push_back(j);
      run.place_of_frame.push_back(place);
    } else {
      if (!members.empty()) {
        const place_recognition::FabMapResult full = fabmap->Compare(words);
        result.declared_new = full.best_log_odds < options.match_log_odds;
      } else {
        result.declared_new = true;
      }
      run.place_of_frame.push_back(fabmap->AddPlace(words));
      members.push_back({j});
    }
    results.push_back(result);
    if (progress) progress(j + 1, frames.size());
  }
  return run;
}

PlaceMapShape DescribePlaces(const PlaceRecognitionFrames& frames, const PlaceGroundTruth& truth,
                             const std::vector<int>& place_of_frame) {
  CheckSizes(frames, truth);
  if (place_of_frame.size() != frames.times.size())
    throw std::invalid_argument("DescribePlaces: one place per frame is needed");
  PlaceMapShape shape;
  std::vector<int> frames_of_place;
  for (const int place : place_of_frame) {
    if (place < 0) throw std::invalid_argument("DescribePlaces: a frame without a place");
    if (place >= static_cast<int>(frames_of_place.size()))
      frames_of_place.resize(static_cast<std::size_t>(place) + 1, 0);
    ++frames_of_place[static_cast<std::size_t>(place)];
  }
  for (const int count : frames_of_place) shape.places += count > 0 ? 1 : 0;
  if (!frames_of_place.empty())
    shape.largest_place_frames = *std::max_element(frames_of_place.begin(), frames_of_place.end());
  shape.largest_place_share =
      frames.size() > 0 ? static_cast<double>(shape.largest_place_frames) / frames.size() : 0.0;
  double places_sum = 0;
  for (int j = 0; j < frames.size(); ++j) {
    bool revisited = false;
    for (int i = 0; i < j && !revisited; ++i)
      revisited = frames.IsCandidate(i, j) && truth.Same(i, j);
    if (!revisited) continue;
    std::set<int> places = {place_of_frame[static_cast<std::size_t>(j)]};
    for (int i = 0; i < frames.size(); ++i) {
      if (truth.Same(i, j)) places.insert(place_of_frame[static_cast<std::size_t>(i)]);
    }
    ++shape.revisited_locations;
    places_sum += static_cast<double>(places.size());
  }
  shape.places_per_revisited_location =
      shape.revisited_locations > 0 ? places_sum / shape.revisited_locations : 0.0;
  return shape;
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
      if (result.has_true_match) {
        result.true_candidate_rank = TrueCandidateRank(
            j, [&](int i) { return scores[static_cast<std::size_t>(i)]; },
            [&](int i) { return frames.IsCandidate(i, j); },
            [&](int i) { return truth.Same(i, j); });
      }
    }
    index->Add(words);
    results.push_back(result);
  }
  return results;
}

}  // namespace stereo_fabmap_slam::evaluation
