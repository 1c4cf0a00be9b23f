#include "test_support.h"

#include <fcntl.h>
#include <sys/file.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <array>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <regex>
#include <sstream>
#include <stdexcept>

#include <gtest/gtest.h>

namespace stereo_fabmap_slam::test {

std::string RepositoryRoot() { return STEREO_FABMAP_SLAM_REPO_ROOT; }

std::string DataRoot() {
  const char* from_environment = std::getenv("STEREO_FABMAP_SLAM_DATA");
  if (from_environment != nullptr && *from_environment != '\0') return from_environment;
  return RepositoryRoot() + "/../shared/data";
}

std::string EurocSequencePath(const std::string& name) {
  const std::string path = DataRoot() + "/euroc/" + name;
  if (!std::filesystem::is_directory(path)) {
    throw std::runtime_error("test data missing: " + path +
                             " (set STEREO_FABMAP_SLAM_DATA to the shared data folder)");
  }
  return path;
}

TemporaryDirectory::TemporaryDirectory() {
  std::string pattern = (std::filesystem::temp_directory_path() / "sfs_test_XXXXXX").string();
  if (mkdtemp(pattern.data()) == nullptr) throw std::runtime_error("mkdtemp failed");
  path_ = pattern;
}

TemporaryDirectory::~TemporaryDirectory() {
  std::error_code ignored;
  std::filesystem::remove_all(path_, ignored);
}

void WriteTextFile(const std::string& path, const std::string& text) {
  std::filesystem::create_directories(std::filesystem::path(path).parent_path());
  std::ofstream file(path);
  file << text;
  if (!file) throw std::runtime_error("cannot write " + path);
}

std::string ReadTextFile(const std::string& path) {
  std::ifstream file(path);
  std::stringstream text;
  text << file.rdbuf();
  return text.str();
}

bool CopyTree(const std::string& from, const std::string& to) {
  std::error_code error;
  std::filesystem::copy(from, to, std::filesystem::copy_options::recursive, error);
  return !error;
}

int RunCommand(const std::string& command, std::string* output) {
  FILE* pipe = popen(command.c_str(), "r");
  if (pipe == nullptr) return -1;
  std::array<char, 4096> buffer;
  output->clear();
  std::size_t n;
  while ((n = std::fread(buffer.data(), 1, buffer.size(), pipe)) > 0)
    output->append(buffer.data(), n);
  const int status = pclose(pipe);
  return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}

namespace {

// Releases an flock(2) lock (and closes its file) when it goes out of scope.
class FileLock {
 public:
  explicit FileLock(const std::string& path)
      : descriptor_(open(path.c_str(), O_CREAT | O_RDWR, 0644)) {
    if (descriptor_ < 0 || flock(descriptor_, LOCK_EX) != 0) {
      throw std::runtime_error("cannot lock " + path);
    }
  }
  ~FileLock() {
    flock(descriptor_, LOCK_UN);
    close(descriptor_);
  }
  FileLock(const FileLock&) = delete;
  FileLock& operator=(const FileLock&) = delete;

 private:
  int descriptor_;
};

// Which build of the renderer wrote a sequence: the program's size and modification time. The
// build relinks the program whenever a library it links (the renderer's) changes.
std::string ProgramFingerprint(const std::string& program) {
  const auto stamp = std::filesystem::last_write_time(program).time_since_epoch().count();
  return std::to_string(std::filesystem::file_size(program)) + " " + std::to_string(stamp) + "\n";
}

}  // namespace

std::string SharedSyntheticSequence(const std::string& make_synthetic_sequence,
                                    const std::string& route, int seconds, int seed,
                                    const std::string& scene, bool with_bag) {
  const std::string cache = STEREO_FABMAP_SLAM_TEST_CACHE;
  const std::string name = (scene == "hall" ? "" : scene + "-") + route + "-" +
                           std::to_string(seconds) + "s-seed" + std::to_string(seed) +
                           (with_bag ? "" : "-no-bag");
  const std::string folder = cache + "/" + name;
  // Written last: a folder without it (a render that was interrupted) is rendered again.
  const std::string fingerprint_file = folder + "/rendered_by";
  std::filesystem::create_directories(cache);
  const FileLock lock(cache + "/" + name + ".lock");
  const std::string fingerprint = ProgramFingerprint(make_synthetic_sequence);
  if (std::filesystem::exists(fingerprint_file) && ReadTextFile(fingerprint_file) == fingerprint) {
    return folder;
  }
  std::filesystem::remove_all(folder);
  std::string output;
  if (RunCommand(make_synthetic_sequence + " --output " + folder + " --route " + route +
                     " --seconds " + std::to_string(seconds) + " --seed " + std::to_string(seed) +
                     " --scene " + scene + (with_bag ? "" : " --no-bag") + " 2>&1",
                 &output) != 0) {
    ADD_FAILURE() << output;
    return "";
  }
  WriteTextFile(fingerprint_file, fingerprint);
  return folder;
}

double JsonNumber(const std::string& json, const std::string& key) {
  std::smatch match;
  if (!std::regex_search(json, match, std::regex("\"" + key + "\": ([-0-9.eE+]+)"))) {
    ADD_FAILURE() << key << " not in " << json;
    return -1;
  }
  return std::stod(match[1]);
}

}  // namespace stereo_fabmap_slam::test
