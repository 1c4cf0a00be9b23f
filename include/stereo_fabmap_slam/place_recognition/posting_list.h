#pragma once

#include <cstdint>
#include <vector>

namespace stereo_fabmap_slam::place_recognition {

// The increasing place ids that showed one word, stored as variable-length gaps (7 bits a byte,
// high bit = more bytes follow): about one byte per place in a dense index instead of four, and
// a query streams the postings, so this is what bounds its time.
class PostingList {
 public:
  // Appending a larger id is O(1); a smaller one re-encodes the list.
  void Insert(std::uint32_t place);
  std::uint32_t size() const { return count_; }
  std::size_t bytes() const { return encoded_.capacity(); }

  // Calls visit(place) for every place, in increasing order.
  template <typename Visit>
  void ForEach(Visit visit) const {
    std::uint32_t place = 0;
    const std::uint8_t* byte = encoded_.data();
    const std::uint8_t* end = byte + encoded_.size();
    while (byte < end) {
      std::uint32_t gap = *byte & 0x7f;
      for (int shift = 7; *byte++ & 0x80; shift += 7)
        gap |= static_cast<std::uint32_t>(*byte & 0x7f) << shift;
      place += gap;
      visit(place);
    }
  }
  std::vector<std::uint32_t> Decode() const;

 private:
  void Append(std::uint32_t gap);

  std::vector<std::uint8_t> encoded_;
  std::uint32_t count_ = 0;
  std::uint32_t last_ = 0;  // the largest id (the first entry is stored as a gap from 0)
};

}  // namespace stereo_fabmap_slam::place_recognition
