#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "stereo_fabmap_slam/place_recognition/posting_list.h"

namespace stereo_fabmap_slam::place_recognition {

// A place: how often it was observed, and for each word it showed, in how many observations.
struct Place {
  std::int32_t observations = 0;
  std::vector<std::int32_t> words;  // sorted
  std::vector<std::uint16_t> hits;  // observations that showed words[i]
};

// The places observed `observations` times that showed a word in `hits` of them: all change a
// query's log-likelihood by the same amount for that word. They are listed by their rank among
// the repeated places (PlaceDatabase::repeated_places()): a query then adds its corrections
// into a small array of repeated places, not all over the scores of the whole map.
struct RepeatedGroup {
  std::int32_t observations;
  std::int32_t hits;
  PostingList ranks;
};

// Places with an inverted index (word -> places that showed it), so that a query visits only the
// places sharing its words. Memory per place: its words (4 + 2 bytes each in the place, about 1
// in the index), independent of the vocabulary size.
class PlaceDatabase {
 public:
  explicit PlaceDatabase(int vocabulary_size = 0)
      : postings_(static_cast<std::size_t>(vocabulary_size)),
        repeated_(static_cast<std::size_t>(vocabulary_size)) {}

  // `words`: sorted, distinct, below the vocabulary size (std::invalid_argument otherwise).
  int AddPlace(const std::vector<int>& words);
  void UpdatePlace(int place, const std::vector<int>& words);  // one more observation of it

  int size() const { return static_cast<int>(places_.size()); }
  int vocabulary_size() const { return static_cast<int>(postings_.size()); }
  const Place& place(int index) const { return places_[static_cast<std::size_t>(index)]; }
  const PostingList& PlacesWith(int word) const {
    return postings_[static_cast<std::size_t>(word)];
  }
  // Observations per place, compact.
  const std::vector<std::int32_t>& observations() const { return observations_; }
  // The places observed more than once, in the order they became so (their rank).
  const std::vector<std::int32_t>& repeated_places() const { return repeated_places_; }
  // The repeated places that showed `word`, by group. A query scores every place through
  // PlacesWith() as if seen once, then corrects these, group by group.
  const std::vector<RepeatedGroup>& RepeatedWith(int word) const {
    return repeated_[static_cast<std::size_t>(word)];
  }
  std::size_t MemoryBytes() const;  // of places and index, for the benchmark

  void Save(const std::string& path) const;
  // Replaces nothing on failure: the caller's database stays as it was (InputError thrown).
  static PlaceDatabase Load(const std::string& path);
  bool operator==(const PlaceDatabase& other) const;

 private:
  void Validate(const std::vector<int>& words) const;
  void Index(int place, int word) {
    postings_[static_cast<std::size_t>(word)].Insert(static_cast<std::uint32_t>(place));
  }
  // Enters or removes a repeated place's word in its group; `rank` as in repeated_places().
  void Group(int rank, int word, int observations, int hits);
  void Ungroup(int rank, int word, int observations, int hits);
  std::vector<RepeatedGroup>::iterator FindGroup(int word, int observations, int hits);
  int RankOf(int place);  // gives a place its rank when it becomes repeated

  std::vector<Place> places_;
  std::vector<std::int32_t> observations_;
  std::vector<PostingList> postings_;                 // per word: every place that showed it
  std::vector<std::vector<RepeatedGroup>> repeated_;  // per word
  std::vector<std::int32_t> repeated_places_;         // by rank
  std::vector<std::int32_t> rank_;                    // per place; -1 while seen once
};

}  // namespace stereo_fabmap_slam::place_recognition
