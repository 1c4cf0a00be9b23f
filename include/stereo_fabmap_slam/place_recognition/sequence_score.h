#pragma once

#include <deque>
#include <vector>

namespace stereo_fabmap_slam::place_recognition {

// Temporal consistency of place matches (SeqSLAM's idea, on FAB-MAP's evidence): a revisit is a
// run of consecutive views that match a run of neighbouring places, while a look-alike corridor
// matches one view here and another there. A place's sequence score is the sum of the log odds
// (against a new place) along the best chain of the last `length` queries that ends at the
// place, each step moving at most `max_step` places back or forward (places in the order they
// were added: consecutive keyframes or images; forward and back, so that a corridor walked the
// other way counts too). A chain may begin at any of those queries (the views before it showed
// new places: log odds 0), so a place never scores below its own view's log odds, and a run of
// matches adds up. Under FAB-MAP's independence of views, the sum is the log odds of "these
// views show this chain of places" against "they show new places", so 0 keeps its meaning as a
// threshold.
struct SequenceScoreOptions {
  // Queries in a chain; 1 scores each query alone (the sequence is off).
  int length = 1;
  // Places a chain may move per query (either way). Per image at 5 frames a second and 1 m/s,
  // or keyframes 0.25 m apart, 3 places is 0.6-0.75 m, faster than walking and than the
  // rendered routes' speeds.
  int max_step = 3;

  void Validate() const;  // throws std::invalid_argument
};

class SequenceScore {
 public:
  explicit SequenceScore(SequenceScoreOptions options);

  // The query's log odds against a new place, one per place in the map (-infinity: the place
  // was no candidate, e.g. the recent past); returns the sequence score of each place. A place
  // a chain's earlier query did not know (added since, or no candidate then) adds nothing to it
  // there: no evidence either way.
  std::vector<double> Push(const std::vector<double>& log_odds);
  // The scores Push would return, without adding the query to the sequence (a view that is no
  // keyframe of it: a relocalization attempt).
  std::vector<double> Peek(const std::vector<double>& log_odds) const;
  // The sequence of views is broken (tracking lost, a new map): chains start afresh.
  void Reset() { history_.clear(); }

 private:
  // The scores of the chains over `queries` (oldest first) that end at the newest one.
  std::vector<double> Score(const std::vector<const std::vector<double>*>& queries) const;

  SequenceScoreOptions options_;
  std::deque<std::vector<double>> history_;  // the last `length` queries' log odds, oldest first
};

}  // namespace stereo_fabmap_slam::place_recognition
