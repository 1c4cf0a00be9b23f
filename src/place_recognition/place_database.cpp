#include "stereo_fabmap_slam/place_recognition/place_database.h"

#include <algorithm>
#include <stdexcept>

#include "stereo_fabmap_slam/io/binary_file.h"

namespace stereo_fabmap_slam::place_recognition {
namespace {

constexpr char kPlaceDatabaseMagic[9] = "SFSPLACE";
constexpr std::uint32_t kPlaceDatabaseVersion = 1;

}  // namespace

void PlaceDatabase::Validate(const std::vector<int>& words) const {
  for (std::size_t i = 0; i < words.size(); ++i) {
    if (words[i] < 0 || words[i] >= vocabulary_size() || (i > 0 && words[i] <= words[i - 1])) {
      throw std::invalid_argument(
          "place words must be sorted, distinct and below the vocabulary size");
    }
  }
}

int PlaceDatabase::AddPlace(const std::vector<int>& words) {
  Validate(words);
  const int index = size();
  Place place;
  place.observations = 1;
  place.words.assign(words.begin(), words.end());
  place.hits.assign(words.size(), 1);
  places_.push_back(std::move(place));
  observations_.push_back(1);
  rank_.push_back(-1);
  for (const int word : words) Index(index, word);
  return index;
}

void PlaceDatabase::UpdatePlace(int index, const std::vector<int>& words) {
  Validate(words);
  Place& place = places_.at(static_cast<std::size_t>(index));
  const int rank = RankOf(index);
  if (place.observations > 1) {
    for (std::size_t i = 0; i < place.words.size(); ++i)
      Ungroup(rank, place.words[i], place.observations, place.hits[i]);
  }
  observations_[static_cast<std::size_t>(index)] = ++place.observations;
  for (const int word : words) {
    const auto position = std::lower_bound(place.words.begin(), place.words.end(), word);
    const std::size_t offset = static_cast<std::size_t>(position - place.words.begin());
    if (position != place.words.end() && *position == word) {
      if (place.hits[offset] < UINT16_MAX) ++place.hits[offset];
    } else {
      place.words.insert(position, word);
      place.hits.insert(place.hits.begin() + static_cast<std::ptrdiff_t>(offset), 1);
      Index(index, word);
    }
  }
  for (std::size_t i = 0; i < place.words.size(); ++i)
    Group(rank, place.words[i], place.observations, place.hits[i]);
}

int PlaceDatabase::RankOf(int place) {
  std::int32_t& rank = rank_[static_cast<std::size_t>(place)];
  if (rank < 0) {
    rank = static_cast<std::int32_t>(repeated_places_.size());
    repeated_places_.push_back(place);
  }
  return rank;
}

std::vector<RepeatedGroup>::iterator PlaceDatabase::FindGroup(int word, int observations,
                                                              int hits) {
  std::vector<RepeatedGroup>& groups = repeated_[static_cast<std::size_t>(word)];
  return std::find_if(groups.begin(), groups.end(), [&](const RepeatedGroup& g) {
    return g.observations == observations && g.hits == hits;
  });
}

void PlaceDatabase::Group(int rank, int word, int observations, int hits) {
  std::vector<RepeatedGroup>& groups = repeated_[static_cast<std::size_t>(word)];
  auto group = FindGroup(word, observations, hits);
  if (group == groups.end()) group = groups.insert(groups.end(), {observations, hits, {}});
  group->ranks.Insert(static_cast<std::uint32_t>(rank));
}

void PlaceDatabase::Ungroup(int rank, int word, int observations, int hits) {
  std::vector<RepeatedGroup>& groups = repeated_[static_cast<std::size_t>(word)];
  const auto group = FindGroup(word, observations, hits);
  if (group == groups.end()) return;
  group->ranks.Erase(static_cast<std::uint32_t>(rank));
  if (group->ranks.size() == 0) groups.erase(group);
}

std::size_t PlaceDatabase::MemoryBytes() const {
  std::size_t bytes = places_.capacity() * (sizeof(Place) + sizeof(std::int32_t)) +
                      postings_.capacity() * sizeof(PostingList) +
                      repeated_.capacity() * sizeof(repeated_[0]) +
                      (repeated_places_.capacity() + rank_.capacity()) * sizeof(std::int32_t);
  for (const Place& p : places_) bytes += p.words.capacity() * 4 + p.hits.capacity() * 2;
  for (const PostingList& list : postings_) bytes += list.bytes();
  for (const std::vector<RepeatedGroup>& groups : repeated_) {
    bytes += groups.capacity() * sizeof(RepeatedGroup);
    for (const RepeatedGroup& group : groups) bytes += group.ranks.bytes();
  }
  return bytes;
}

void PlaceDatabase::Save(const std::string& path) const {
  io::BinaryWriter writer;
  writer.Put<std::int32_t>(vocabulary_size());
  writer.Put<std::uint64_t>(places_.size());
  for (const Place& place : places_) {
    writer.Put<std::int32_t>(place.observations);
    writer.PutVector(place.words);
    writer.PutVector(place.hits);
  }
  io::WriteBinaryFile(path, kPlaceDatabaseMagic, kPlaceDatabaseVersion, writer.bytes());
}

PlaceDatabase PlaceDatabase::Load(const std::string& path) {
  io::BinaryReader reader = io::ReadBinaryFile(path, kPlaceDatabaseMagic, kPlaceDatabaseVersion);
  const auto vocabulary = reader.Get<std::int32_t>();
  // The index has an entry per word, allocated up front: a corrupt size must not ask for
  // gigabytes. FAB-MAP vocabularies have thousands to a hundred thousand words (the default
  // 10,000); a million is far beyond any and still only tens of megabytes of index.
  constexpr std::int32_t kMaxVocabularySize = 1'000'000;
  if (vocabulary < 1 || vocabulary > kMaxVocabularySize) {
    reader.Fail("bad vocabulary size " + std::to_string(vocabulary));
  }
  PlaceDatabase database(vocabulary);
  const auto count = reader.Get<std::uint64_t>();
  for (std::uint64_t i = 0; i < count; ++i) {
    Place place;
    place.observations = reader.Get<std::int32_t>();
    place.words = reader.GetVector<std::int32_t>();
    place.hits = reader.GetVector<std::uint16_t>();
    if (place.observations < 1 || place.hits.size() != place.words.size()) reader.Fail("bad place");
    try {
      database.Validate(place.words);
    } catch (const std::invalid_argument& error) {
      reader.Fail(error.what());
    }
    const int index = database.size();
    database.rank_.push_back(-1);
    const int rank = place.observations > 1 ? database.RankOf(index) : -1;
    for (std::size_t w = 0; w < place.words.size(); ++w) {
      if (place.hits[w] < 1 || place.hits[w] > place.observations) reader.Fail("bad hit count");
      database.Index(index, place.words[w]);
      if (rank >= 0) database.Group(rank, place.words[w], place.observations, place.hits[w]);
    }
    database.observations_.push_back(place.observations);
    database.places_.push_back(std::move(place));
  }
  reader.ExpectEnd();
  return database;
}

bool PlaceDatabase::operator==(const PlaceDatabase& other) const {
  if (vocabulary_size() != other.vocabulary_size() || size() != other.size()) return false;
  for (int i = 0; i < size(); ++i) {
    const Place &a = place(i), &b = other.place(i);
    if (a.observations != b.observations || a.words != b.words || a.hits != b.hits) return false;
  }
  return true;
}

}  // namespace stereo_fabmap_slam::place_recognition
