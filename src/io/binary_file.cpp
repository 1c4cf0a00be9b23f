#include "stereo_fabmap_slam/io/binary_file.h"

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iterator>

#include "stereo_fabmap_slam/io/input_error.h"

namespace stereo_fabmap_slam::io {

void BinaryReader::ExpectEnd() const {
  if (offset_ != payload_.size()) Fail("unexpected bytes after the content");
}

void BinaryReader::Fail(const std::string& what) const {
  throw FileError(source_, 0, "corrupt file: " + what);
}

std::uint64_t Fnv1a64(const std::uint8_t* data, std::size_t size) {
  std::uint64_t hash = 14695981039346656037ULL;
  for (std::size_t i = 0; i < size; ++i) {
    hash ^= data[i];
    hash *= 1099511628211ULL;
  }
  return hash;
}

void WriteBinaryFile(const std::string& path, const char (&magic)[9], std::uint32_t version,
                     const std::vector<std::uint8_t>& payload) {
  // Refused before anything is written: a failed save leaves no file behind.
  if (path.empty()) throw FileError(path, 0, "no file named (an empty path)");
  if (std::filesystem::is_directory(path)) throw FileError(path, 0, "is a directory");
  const std::string temporary = path + ".partial";
  try {
    {
      std::ofstream out(temporary, std::ios::binary | std::ios::trunc);
      if (!out) throw FileError(path, 0, "cannot open for writing");
      const std::uint64_t length = payload.size(),
                          checksum = Fnv1a64(payload.data(), payload.size());
      out.write(magic, 8);
      out.write(reinterpret_cast<const char*>(&version), sizeof(version));
      out.write(reinterpret_cast<const char*>(&length), sizeof(length));
      out.write(reinterpret_cast<const char*>(payload.data()),
                static_cast<std::streamsize>(payload.size()));
      out.write(reinterpret_cast<const char*>(&checksum), sizeof(checksum));
      if (!out) throw FileError(path, 0, "write error");
    }
    std::filesystem::rename(temporary, path);
  } catch (const std::filesystem::filesystem_error& error) {
    std::error_code ignored;
    std::filesystem::remove(temporary, ignored);
    throw FileError(path, 0, std::string("cannot replace: ") + error.code().message());
  } catch (...) {
    std::error_code ignored;  // a full disk: what was written goes
    std::filesystem::remove(temporary, ignored);
    throw;
  }
}

BinaryReader ReadBinaryFile(const std::string& path, const char (&magic)[9],
                            std::uint32_t version) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw FileError(path, 0, "cannot open file");
  const std::vector<std::uint8_t> file((std::istreambuf_iterator<char>(in)),
                                       std::istreambuf_iterator<char>());
  constexpr std::size_t kHeader = 8 + sizeof(std::uint32_t) + sizeof(std::uint64_t);
  if (file.size() < kHeader || std::memcmp(file.data(), magic, 8) != 0) {
    throw FileError(path, 0,
                    std::string("not a ") + std::string(magic, 8) + " file (wrong magic number)");
  }
  std::uint32_t file_version;
  std::uint64_t length;
  std::memcpy(&file_version, file.data() + 8, sizeof(file_version));
  std::memcpy(&length, file.data() + 12, sizeof(length));
  if (file_version != version) {
    throw FileError(path, 0,
                    "version " + std::to_string(file_version) + ", this build reads version " +
                        std::to_string(version));
  }
  if (file.size() != kHeader + length + sizeof(std::uint64_t)) {
    throw FileError(path, 0,
                    "truncated or padded file: " + std::to_string(file.size()) +
                        " bytes, header says " +
                        std::to_string(kHeader + length + sizeof(std::uint64_t)));
  }
  std::uint64_t checksum;
  std::memcpy(&checksum, file.data() + kHeader + length, sizeof(checksum));
  if (checksum != Fnv1a64(file.data() + kHeader, length))
    throw FileError(path, 0, "checksum mismatch: the file is corrupt");
  return BinaryReader(
      std::vector<std::uint8_t>(file.begin() + kHeader, file.begin() + kHeader + length), path);
}

}  // namespace stereo_fabmap_slam::io
