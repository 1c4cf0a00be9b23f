#pragma once

// Deterministic mutants of the package's binary files (io/binary_file: 8-byte magic, uint32
// version, uint64 payload length, payload, uint64 FNV-1a checksum), and a harness that loads
// each under a bound on the address space: a loader must refuse a mutant with io::InputError or
// load it, never crash, hang or allocate beyond the bound (std::bad_alloc would say it tried).

#include <sys/resource.h>

#include <cstdint>
#include <cstring>
#include <fstream>
#include <functional>
#include <random>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "stereo_fabmap_slam/io/binary_file.h"
#include "stereo_fabmap_slam/io/input_error.h"

namespace stereo_fabmap_slam::test {

struct FileMutant {
  std::vector<char> bytes;
  // The payload was changed and its checksum recomputed: what only the parser can catch.
  bool checksum_fixed = false;
  std::string what;
};

inline constexpr std::size_t kBinaryHeaderBytes = 8 + 4 + 8;

// The i-th mutant of `original` (one at a time: a few thousand copies of a map would be
// gigabytes), in equal shares: random bit flips anywhere, truncations, appended bytes, payload
// bytes changed with the checksum fixed, and 8-byte payload words set to huge values (counts and
// sizes a loader must not trust) with the checksum fixed.
inline FileMutant MakeFileMutant(const std::vector<char>& original, int i,
                                 std::mt19937_64& random) {
  const auto below = [&](std::size_t n) {
    return std::uniform_int_distribution<std::size_t>(0, n - 1)(random);
  };
  const std::size_t payload_begin = kBinaryHeaderBytes;
  const std::size_t payload_end = original.size() - 8;
  const auto fix_checksum = [&](std::vector<char>* bytes) {
    const std::uint64_t checksum =
        io::Fnv1a64(reinterpret_cast<const std::uint8_t*>(bytes->data()) + payload_begin,
                    payload_end - payload_begin);
    std::memcpy(bytes->data() + payload_end, &checksum, 8);
  };
  {
    FileMutant mutant{original, false, ""};
    std::vector<char>& bytes = mutant.bytes;
    switch (i % 5) {
      case 0: {
        const std::size_t flips = 1 + below(8);
        for (std::size_t f = 0; f < flips; ++f) {
          bytes[below(bytes.size())] ^= static_cast<char>(1 << below(8));
        }
        mutant.what = "bit flips";
        break;
      }
      case 1:
        bytes.resize(below(bytes.size()));
        mutant.what = "truncated to " + std::to_string(bytes.size());
        break;
      case 2: {
        const std::size_t extra = 1 + below(64);
        for (std::size_t e = 0; e < extra; ++e) bytes.push_back(static_cast<char>(below(256)));
        mutant.what = "appended bytes";
        break;
      }
      case 3: {
        const std::size_t changes = 1 + below(4);
        for (std::size_t c = 0; c < changes; ++c) {
          bytes[payload_begin + below(payload_end - payload_begin)] = static_cast<char>(below(256));
        }
        fix_checksum(&bytes);
        mutant.checksum_fixed = true;
        mutant.what = "payload bytes, checksum fixed";
        break;
      }
      default: {
        if (payload_end - payload_begin < 8) break;
        const std::uint64_t huge[] = {UINT64_MAX, 1ull << 62, 1ull << 40, 1ull << 31,
                                      0xFFFFFFFFull};
        const std::uint64_t value = huge[below(5)];
        std::memcpy(bytes.data() + payload_begin + below(payload_end - payload_begin - 7), &value,
                    8);
        fix_checksum(&bytes);
        mutant.checksum_fixed = true;
        mutant.what = "a huge payload word, checksum fixed";
        break;
      }
    }
    return mutant;
  }
}

inline std::vector<char> ReadFileBytes(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  return std::vector<char>(std::istreambuf_iterator<char>(in), {});
}

inline void WriteFileBytes(const std::string& path, const std::vector<char>& bytes) {
  std::ofstream(path, std::ios::binary)
      .write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
}

struct FuzzCounts {
  int refused = 0, loaded = 0;
};

// Loads every mutant of the file at `path` with `load` (which throws io::InputError to refuse)
// while the address space may grow by at most `bound_bytes`. A mutant whose checksum was not
// fixed must be refused unless it equals the original.
inline FuzzCounts LoadMutants(const std::string& path, int count, std::uint64_t seed,
                              std::size_t bound_bytes,
                              const std::function<void(const std::string&)>& load) {
  const std::vector<char> original = ReadFileBytes(path);
  const std::string mutant_path = path + ".mutant";
  rlimit previous{};
  getrlimit(RLIMIT_AS, &previous);
  // The current size of the address space, from /proc/self/statm (pages).
  std::size_t pages = 0;
  std::ifstream("/proc/self/statm") >> pages;
  const rlimit bounded{pages * 4096 + bound_bytes, previous.rlim_max};
  FuzzCounts counts;
  std::mt19937_64 random(seed);
  for (int i = 0; i < count; ++i) {
    const FileMutant mutant = MakeFileMutant(original, i, random);
    WriteFileBytes(mutant_path, mutant.bytes);
    setrlimit(RLIMIT_AS, &bounded);
    std::string failure;
    bool loaded = false;
    try {
      load(mutant_path);
      loaded = true;
    } catch (const io::InputError&) {
      ++counts.refused;
    } catch (const std::bad_alloc&) {
      failure = "allocated beyond the bound";
    } catch (const std::exception& error) {
      failure = std::string("threw something other than InputError: ") + error.what();
    }
    setrlimit(RLIMIT_AS, &previous);
    EXPECT_EQ(failure, "") << mutant.what;
    if (loaded) {
      ++counts.loaded;
      EXPECT_TRUE(mutant.checksum_fixed || mutant.bytes == original)
          << "a damaged file was loaded: " << mutant.what;
    }
  }
  return counts;
}

}  // namespace stereo_fabmap_slam::test
