#pragma once

#include <optional>
#include <set>
#include <string>
#include <vector>

#include "stereo_fabmap_slam/io/yaml_file.h"

namespace stereo_fabmap_slam::io {

// Fills an Options struct from one YAML mapping: every key is optional (the struct's default
// stays), a key of the wrong type is an error naming file and line, and so is a key no Read()
// asked for (a typo must not silently leave a default in place).
class OptionReader {
 public:
  // `node` may be undefined (section absent): then every Read() keeps the default.
  OptionReader(const YamlFile& file, const YAML::Node& node, std::string section);
  ~OptionReader() = default;

  void Read(const std::string& key, double* value);
  void Read(const std::string& key, int* value);
  void Read(const std::string& key, bool* value);
  void Read(const std::string& key, std::string* value);
  // Throws InputError listing the keys of the section that no Read() asked for.
  void RejectUnknownKeys() const;

 private:
  std::optional<YAML::Node> Find(const std::string& key);
  [[noreturn]] void Fail(const std::string& key, const char* expected) const;

  const YamlFile& file_;
  YAML::Node node_;
  std::string section_;
  std::set<std::string> known_;
};

}  // namespace stereo_fabmap_slam::io
