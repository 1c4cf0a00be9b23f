#pragma once

#include <string>

namespace stereo_fabmap_slam::test {

// Root of the shared test data: $STEREO_FABMAP_SLAM_DATA, or ../shared/data beside the repository.
std::string DataRoot();
// An EuRoC sequence under DataRoot()/euroc; fails the calling test if it is missing.
std::string EurocSequencePath(const std::string& name);
std::string RepositoryRoot();

// A fresh, empty folder removed again when the object goes out of scope.
class TemporaryDirectory {
 public:
  TemporaryDirectory();
  ~TemporaryDirectory();
  TemporaryDirectory(const TemporaryDirectory&) = delete;
  TemporaryDirectory& operator=(const TemporaryDirectory&) = delete;
  const std::string& path() const { return path_; }

 private:
  std::string path_;
};

// Writes `text` to `path` (creating parent folders).
void WriteTextFile(const std::string& path, const std::string& text);
std::string ReadTextFile(const std::string& path);
// Copies a folder tree (cp -r); returns false on failure.
bool CopyTree(const std::string& from, const std::string& to);
// Runs a shell command, returns its exit status and fills *output with stdout.
int RunCommand(const std::string& command, std::string* output);

// The folder of a sequence that `make_synthetic_sequence` (the program at that path) renders,
// with its bag, for `route`, `seconds` and `seed`. Rendering is most of the time of the tests
// that need one, so tests that ask for the same sequence share it: it is kept in the build
// folder (STEREO_FABMAP_SLAM_TEST_CACHE), rendered by the first test that asks (the others wait
// on a file lock), and rendered again when the program has been rebuilt since. Tests must only
// read it. Fails the calling test and returns "" if rendering fails. `scene`: "hall" or
// "office"; with_bag false renders the images alone (for run_dataset; no rostest plays it).
std::string SharedSyntheticSequence(const std::string& make_synthetic_sequence,
                                    const std::string& route, int seconds, int seed,
                                    const std::string& scene = "hall", bool with_bag = true);

// The number after "key": in a one-line JSON object (run_dataset's summary.json); records a test
// failure and returns -1 if the key is missing.
double JsonNumber(const std::string& json, const std::string& key);

}  // namespace stereo_fabmap_slam::test
