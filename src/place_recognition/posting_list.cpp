#include "stereo_fabmap_slam/place_recognition/posting_list.h"

#include <algorithm>

namespace stereo_fabmap_slam::place_recognition {

void PostingList::Append(std::uint32_t gap) {
  while (gap >= 0x80) {
    encoded_.push_back(static_cast<std::uint8_t>(gap | 0x80));
    gap >>= 7;
  }
  encoded_.push_back(static_cast<std::uint8_t>(gap));
}

std::vector<std::uint32_t> PostingList::Decode() const {
  std::vector<std::uint32_t> places;
  places.reserve(count_);
  ForEach([&](std::uint32_t place) { places.push_back(place); });
  return places;
}

void PostingList::Insert(std::uint32_t place) {
  if (count_ == 0 || place > last_) {
    Append(count_ == 0 ? place : place - last_);
    last_ = place;
    ++count_;
    return;
  }
  std::vector<std::uint32_t> places = Decode();
  const auto position = std::lower_bound(places.begin(), places.end(), place);
  if (position != places.end() && *position == place) return;
  places.insert(position, place);
  encoded_.clear();
  count_ = 0;
  for (const std::uint32_t p : places) {
    Append(count_ == 0 ? p : p - last_);
    last_ = p;
    ++count_;
  }
}

}  // namespace stereo_fabmap_slam::place_recognition
