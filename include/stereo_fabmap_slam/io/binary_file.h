#pragma once

#include <cstdint>
#include <cstring>
#include <string>
#include <type_traits>
#include <vector>

namespace stereo_fabmap_slam::io {

// Builds the payload of a binary file: plain values and vectors of them, little-endian as the
// machine stores them (x86-64, aarch64).
class BinaryWriter {
 public:
  template <typename T>
  void Put(const T& value) {
    static_assert(std::is_trivially_copyable_v<T>);
    const auto* bytes = reinterpret_cast<const std::uint8_t*>(&value);
    buffer_.insert(buffer_.end(), bytes, bytes + sizeof(T));
  }
  template <typename T>
  void PutVector(const std::vector<T>& values) {
    static_assert(std::is_trivially_copyable_v<T>);
    Put<std::uint64_t>(values.size());
    const auto* bytes = reinterpret_cast<const std::uint8_t*>(values.data());
    buffer_.insert(buffer_.end(), bytes, bytes + values.size() * sizeof(T));
  }
  const std::vector<std::uint8_t>& bytes() const { return buffer_; }

 private:
  std::vector<std::uint8_t> buffer_;
};

// Reads a payload back; every read is bounds-checked and throws InputError naming the file.
class BinaryReader {
 public:
  BinaryReader(std::vector<std::uint8_t> payload, std::string source)
      : payload_(std::move(payload)), source_(std::move(source)) {}

  template <typename T>
  T Get() {
    static_assert(std::is_trivially_copyable_v<T>);
    Need(sizeof(T));
    T value;
    std::memcpy(&value, payload_.data() + offset_, sizeof(T));
    offset_ += sizeof(T);
    return value;
  }
  template <typename T>
  std::vector<T> GetVector(std::uint64_t max_count = UINT64_MAX) {
    const auto count = Get<std::uint64_t>();
    if (count > max_count || count > (payload_.size() - offset_) / sizeof(T))
      Fail("a vector is too long");
    std::vector<T> values(count);
    // An empty vector's data() may be null, and memcpy from or to null is undefined even for
    // zero bytes (UBSan reports it).
    if (count > 0) std::memcpy(values.data(), payload_.data() + offset_, count * sizeof(T));
    offset_ += count * sizeof(T);
    return values;
  }
  // Throws unless every byte was read: a payload longer than its content is corrupt too.
  void ExpectEnd() const;
  [[noreturn]] void Fail(const std::string& what) const;

 private:
  void Need(std::size_t bytes) const {
    if (payload_.size() - offset_ < bytes) Fail("payload ends early");
  }

  std::vector<std::uint8_t> payload_;
  std::string source_;
  std::size_t offset_ = 0;
};

// A file = 8-byte magic, uint32 version, uint64 payload length, payload, uint64 FNV-1a checksum
// of the payload. Writing goes through a temporary file renamed into place, so that a crash
// never leaves half a file under the real name.
void WriteBinaryFile(const std::string& path, const char (&magic)[9], std::uint32_t version,
                     const std::vector<std::uint8_t>& payload);
// Returns the payload, or throws InputError saying what is wrong: unreadable, another kind of
// file, another version, truncated, or failing the checksum.
BinaryReader ReadBinaryFile(const std::string& path, const char (&magic)[9], std::uint32_t version);

std::uint64_t Fnv1a64(const std::uint8_t* data, std::size_t size);

}  // namespace stereo_fabmap_slam::io
