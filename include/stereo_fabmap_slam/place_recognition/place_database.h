#pragma once

#include <cstdint>
#include <string>
#include <vector>

namespace stereo_fabmap_slam::place_recognition {

// A place: how often it was observed, and for each word it showed, in how many observations.
struct Place {
  std::int32_t observations = 0;
  std::vector<std::int32_t> words;  // sorted
  std::vector<std::uint16_t> hits;  // observations that showed words[i]
};

// Places with an inverted index (word -> places that showed it), so that a query visits only the
// places sharing its words. Memory per place: its words (4 + 2 bytes each, twice: the place and
// the index), independent of the vocabulary size.
class PlaceDatabase {
 public:
  explicit PlaceDatabase(int vocabulary_size = 0)
      : postings_(static_cast<std::size_t>(vocabulary_size)) {}

  // `words`: sorted, distinct, below the vocabulary size (std::invalid_argument otherwise).
  int AddPlace(const std::vector<int>& words);
  void UpdatePlace(int place, const std::vector<int>& words);  // one more observation of it

  int size() const { return static_cast<int>(places_.size()); }
  int vocabulary_size() const { return static_cast<int>(postings_.size()); }
  const Place& place(int index) const { return places_[static_cast<std::size_t>(index)]; }
  const std::vector<std::uint32_t>& PlacesWith(int word) const {
    return postings_[static_cast<std::size_t>(word)];
  }
  const std::vector<std::uint16_t>& HitsOf(int word) const {
    return posting_hits_[static_cast<std::size_t>(word)];
  }
  std::size_t MemoryBytes() const;  // of places and index, for the benchmark

  void Save(const std::string& path) const;
  // Replaces nothing on failure: the caller's database stays as it was (InputError thrown).
  static PlaceDatabase Load(const std::string& path);
  bool operator==(const PlaceDatabase& other) const;

 private:
  void Validate(const std::vector<int>& words) const;
  void Index(int place, int word, std::uint16_t hits);

  std::vector<Place> places_;
  std::vector<std::vector<std::uint32_t>> postings_;  // per word, increasing place ids
  std::vector<std::vector<std::uint16_t>> posting_hits_ =
      std::vector<std::vector<std::uint16_t>>(postings_.size());
};

}  // namespace stereo_fabmap_slam::place_recognition
