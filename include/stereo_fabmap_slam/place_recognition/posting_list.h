#pragma once

#include <cstdint>
#include <vector>

namespace stereo_fabmap_slam::place_recognition {

// The place ids that showed one word. Increasing ids are stored as variable-length gaps (7 bits
// a byte, high bit = more bytes follow): about one byte per place in a dense index instead of
// four, and a query streams the postings, so this is what bounds its time. Ids inserted below the
// largest (an old place seen again) wait in a short unsorted tail until they are merged in.
class PostingList {
 public:
  // `place` must not be in the list yet. The largest id so far is appended in O(1); a smaller
  // one joins the tail, which is merged once it holds 1/64 of the list (amortised O(1)).
  void Insert(std::uint32_t place);
  // Removes `place` if present, in O(size()).
  void Erase(std::uint32_t place);
  std::uint32_t size() const { return count_ + static_cast<std::uint32_t>(late_.size()); }
  std::size_t bytes() const { return encoded_.capacity() + late_.capacity() * sizeof(late_[0]); }

  // scores[place] += value for every place of the list.
  void AddTo(float value, float* scores) const;
  // The same for two lists in one loop: their two independent decoding chains keep a core
  // busier than one list after the other (7.8 -> 6.9 ms for 10 M postings, docs/benchmarks.md).
  static void AddTo(const PostingList& a, float a_value, const PostingList& b, float b_value,
                    float* scores);

  // Calls visit(place) for every place, in no particular order.
  template <typename Visit>
  void ForEach(Visit visit) const {
    std::uint32_t place = 0;
    const std::uint8_t* byte = encoded_.data();
    const std::uint8_t* end = byte + encoded_.size();
    while (byte < end) {
      place += NextGap(&byte);
      visit(place);
    }
    for (const std::uint32_t late : late_) visit(late);
  }
  std::vector<std::uint32_t> Decode() const;  // in increasing order

 private:
  void Append(std::uint32_t place);
  void Encode(const std::vector<std::uint32_t>& sorted);
  // Decodes the gap at *byte and moves past it; one byte (gap < 128) is the likely case.
  static std::uint32_t NextGap(const std::uint8_t** byte) {
    std::uint32_t gap = *(*byte)++;
    if (__builtin_expect(gap & 0x80, 0)) {
      gap &= 0x7f;
      int shift = 7;
      do {
        gap |= static_cast<std::uint32_t>(**byte & 0x7f) << shift;
        shift += 7;
      } while (*(*byte)++ & 0x80);
    }
    return gap;
  }

  std::vector<std::uint8_t> encoded_;
  std::uint32_t count_ = 0;          // ids in encoded_
  std::uint32_t last_ = 0;           // the largest encoded id (the first is stored as a gap from 0)
  std::vector<std::uint32_t> late_;  // ids below last_, unsorted
};

}  // namespace stereo_fabmap_slam::place_recognition
