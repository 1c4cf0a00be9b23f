#include "stereo_fabmap_slam/place_recognition/posting_list.h"

#include <algorithm>

namespace stereo_fabmap_slam::place_recognition {

void PostingList::Append(std::uint32_t place) {
  std::uint32_t gap = count_ == 0 ? place : place - last_;
  while (gap >= 0x80) {
    encoded_.push_back(static_cast<std::uint8_t>(gap | 0x80));
    gap >>= 7;
  }
  encoded_.push_back(static_cast<std::uint8_t>(gap));
  last_ = place;
  ++count_;
}

void PostingList::Encode(const std::vector<std::uint32_t>& sorted) {
  encoded_.clear();
  late_.clear();
  count_ = 0;
  last_ = 0;
  for (const std::uint32_t place : sorted) Append(place);
}

std::vector<std::uint32_t> PostingList::Decode() const {
  std::vector<std::uint32_t> places;
  places.reserve(size());
  ForEach([&](std::uint32_t place) { places.push_back(place); });  // encoded ids, then the tail
  const auto tail = places.begin() + count_;
  std::sort(tail, places.end());
  std::inplace_merge(places.begin(), tail, places.end());
  return places;
}

void PostingList::Insert(std::uint32_t place) {
  if (count_ == 0 || place > last_) {
    Append(place);
    return;
  }
  late_.push_back(place);
  // A query reaches the tail's places in no order, at several times the cost of a streamed
  // posting, so the tail stays short: merging costs O(size()) every size()/64 inserts.
  if (late_.size() > count_ / 64 + 16) Encode(Decode());
}

void PostingList::Erase(std::uint32_t place) {
  std::vector<std::uint32_t> places = Decode();
  const auto position = std::lower_bound(places.begin(), places.end(), place);
  if (position == places.end() || *position != place) return;
  places.erase(position);
  Encode(places);
}

void PostingList::AddTo(float value, float* scores) const {
  ForEach([&](std::uint32_t place) { scores[place] += value; });
}

void PostingList::AddTo(const PostingList& a, float a_value, const PostingList& b, float b_value,
                        float* scores) {
  const std::uint8_t *a_byte = a.encoded_.data(), *a_end = a_byte + a.encoded_.size();
  const std::uint8_t *b_byte = b.encoded_.data(), *b_end = b_byte + b.encoded_.size();
  std::uint32_t a_place = 0, b_place = 0;
  while (a_byte < a_end && b_byte < b_end) {
    a_place += NextGap(&a_byte);
    b_place += NextGap(&b_byte);
    scores[a_place] += a_value;
    scores[b_place] += b_value;
  }
  while (a_byte < a_end) {
    a_place += NextGap(&a_byte);
    scores[a_place] += a_value;
  }
  while (b_byte < b_end) {
    b_place += NextGap(&b_byte);
    scores[b_place] += b_value;
  }
  for (const std::uint32_t place : a.late_) scores[place] += a_value;
  for (const std::uint32_t place : b.late_) scores[place] += b_value;
}

}  // namespace stereo_fabmap_slam::place_recognition
