#include "stereo_fabmap_slam/place_recognition/place_database.h"

#include <algorithm>
#include <stdexcept>

#include "stereo_fabmap_slam/io/binary_file.h"

namespace stereo_fabmap_slam::place_recognition {
namespace {

constexpr char kMagic[9] = "SFSPLACE";
constexpr std::uint32_t kVersion = 1;

}  // namespace

void PlaceDatabase::Validate(const std::vector<int>& words) const {
  for (std::size_t i = 0; i < words.size(); ++i) {
    if (words[i] < 0 || words[i] >= vocabulary_size() || (i > 0 && words[i] <= words[i - 1])) {
      throw std::invalid_argument(
          "place words must be sorted, distinct and below the vocabulary size");
    }
  }
}

void PlaceDatabase::Index(int place, int word, std::uint16_t hits) {
  std::vector<std::uint32_t>& list = postings_[static_cast<std::size_t>(word)];
  std::vector<std::uint16_t>& list_hits = posting_hits_[static_cast<std::size_t>(word)];
  const auto position =
      std::lower_bound(list.begin(), list.end(), static_cast<std::uint32_t>(place));
  const std::size_t offset = static_cast<std::size_t>(position - list.begin());
  if (position != list.end() && *position == static_cast<std::uint32_t>(place)) {
    list_hits[offset] = hits;
  } else {
    list.insert(position, static_cast<std::uint32_t>(place));
    list_hits.insert(list_hits.begin() + static_cast<std::ptrdiff_t>(offset), hits);
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
  for (const int word : words) Index(index, word, 1);
  return index;
}

void PlaceDatabase::UpdatePlace(int index, const std::vector<int>& words) {
  Validate(words);
  Place& place = places_.at(static_cast<std::size_t>(index));
  ++place.observations;
  for (const int word : words) {
    const auto position = std::lower_bound(place.words.begin(), place.words.end(), word);
    const std::size_t offset = static_cast<std::size_t>(position - place.words.begin());
    if (position != place.words.end() && *position == word) {
      if (place.hits[offset] < UINT16_MAX) ++place.hits[offset];
    } else {
      place.words.insert(position, word);
      place.hits.insert(place.hits.begin() + static_cast<std::ptrdiff_t>(offset), 1);
    }
    Index(index, word, place.hits[offset]);
  }
}

std::size_t PlaceDatabase::MemoryBytes() const {
  std::size_t bytes =
      places_.capacity() * sizeof(Place) + postings_.capacity() * 2 * sizeof(std::vector<int>);
  for (const Place& p : places_) bytes += p.words.capacity() * 4 + p.hits.capacity() * 2;
  for (std::size_t w = 0; w < postings_.size(); ++w)
    bytes += postings_[w].capacity() * 4 + posting_hits_[w].capacity() * 2;
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
  io::WriteBinaryFile(path, kMagic, kVersion, writer.bytes());
}

PlaceDatabase PlaceDatabase::Load(const std::string& path) {
  io::BinaryReader reader = io::ReadBinaryFile(path, kMagic, kVersion);
  const auto vocabulary = reader.Get<std::int32_t>();
  if (vocabulary < 1) reader.Fail("bad vocabulary size");
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
    for (std::size_t w = 0; w < place.words.size(); ++w) {
      if (place.hits[w] < 1 || place.hits[w] > place.observations) reader.Fail("bad hit count");
      database.Index(static_cast<int>(database.places_.size()), place.words[w], place.hits[w]);
    }
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
