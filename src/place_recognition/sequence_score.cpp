#include "stereo_fabmap_slam/place_recognition/sequence_score.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

namespace stereo_fabmap_slam::place_recognition {

void SequenceScoreOptions::Validate() const {
  if (length < 1) {
    throw std::invalid_argument("sequence length must be at least 1, got " +
                                std::to_string(length));
  }
  if (max_step < 0) {
    throw std::invalid_argument("sequence max_step must not be negative, got " +
                                std::to_string(max_step));
  }
}

SequenceScore::SequenceScore(SequenceScoreOptions options) : options_(options) {
  options_.Validate();
}

std::vector<double> SequenceScore::Push(const std::vector<double>& log_odds) {
  history_.push_back(log_odds);
  while (static_cast<int>(history_.size()) > options_.length) history_.pop_front();
  std::vector<const std::vector<double>*> queries;
  for (const std::vector<double>& query : history_) queries.push_back(&query);
  return Score(queries);
}

std::vector<double> SequenceScore::Peek(const std::vector<double>& log_odds) const {
  // The newest length - 1 queries of the sequence, then this one: no copy of the history.
  std::vector<const std::vector<double>*> queries;
  const std::size_t kept = std::min(history_.size(), static_cast<std::size_t>(options_.length - 1));
  for (std::size_t k = history_.size() - kept; k < history_.size(); ++k)
    queries.push_back(&history_[k]);
  queries.push_back(&log_odds);
  return Score(queries);
}

std::vector<double> SequenceScore::Score(
    const std::vector<const std::vector<double>*>& queries) const {
  const std::vector<double>& log_odds = *queries.back();
  // What a query adds to a chain at a place: its log odds there, or nothing if it had none.
  const auto evidence = [](const std::vector<double>& query, long place) {
    if (place < 0 || place >= static_cast<long>(query.size())) return 0.0;
    const double value = query[static_cast<std::size_t>(place)];
    return std::isfinite(value) ? value : 0.0;
  };
  // Dynamic programming from the oldest query: best[p] = the best chain ending at place p.
  const long places = static_cast<long>(log_odds.size());
  std::vector<double> best(static_cast<std::size_t>(places), 0.0);
  std::vector<double> next(best.size());
  const long step = options_.max_step;
  for (std::size_t k = 0; k < queries.size(); ++k) {
    for (long p = 0; p < places; ++p) {
      // A chain may start at any query: the earlier views may have shown new places, whose log
      // odds against a new place are 0 (Smith-Waterman's local alignment). So a revisit that
      // begins now, or a place whose neighbours lie far apart in the map (where a lap closes),
      // keeps at least its own evidence.
      double previous = 0.0;
      if (k > 0) {
        for (long q = std::max(0L, p - step); q <= std::min(places - 1, p + step); ++q) {
          previous = std::max(previous, best[static_cast<std::size_t>(q)]);
        }
      }
      next[static_cast<std::size_t>(p)] = previous + evidence(*queries[k], p);
    }
    best.swap(next);
  }
  // A place that was no candidate now stays none, whatever its chain.
  for (long p = 0; p < places; ++p) {
    if (!std::isfinite(log_odds[static_cast<std::size_t>(p)])) {
      best[static_cast<std::size_t>(p)] = log_odds[static_cast<std::size_t>(p)];
    }
  }
  return best;
}

}  // namespace stereo_fabmap_slam::place_recognition
