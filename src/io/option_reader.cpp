#include "stereo_fabmap_slam/io/option_reader.h"

#include "stereo_fabmap_slam/io/csv_reader.h"

namespace stereo_fabmap_slam::io {

OptionReader::OptionReader(const YamlFile& file, const YAML::Node& node, std::string section)
    : file_(file), node_(node), section_(std::move(section)) {
  if (node_.IsDefined() && !node_.IsNull() && !node_.IsMap()) {
    throw FileError(file_.source(), node_.Mark().line + 1, "'" + section_ + "' must be a mapping");
  }
}

std::optional<YAML::Node> OptionReader::Find(const std::string& key) {
  known_.insert(key);
  if (!node_.IsMap() || !node_[key].IsDefined()) return std::nullopt;
  return node_[key];
}

void OptionReader::Fail(const std::string& key, const char* expected) const {
  throw FileError(file_.source(), node_[key].Mark().line + 1,
                  section_ + "." + key + " must be " + expected);
}

void OptionReader::Read(const std::string& key, double* value) {
  if (const std::optional<YAML::Node> node = Find(key)) {
    try {
      *value = node->as<double>();
    } catch (const YAML::Exception&) {
      Fail(key, "a number");
    }
  }
}

void OptionReader::Read(const std::string& key, int* value) {
  if (const std::optional<YAML::Node> node = Find(key)) {
    try {
      *value = node->as<int>();
    } catch (const YAML::Exception&) {
      Fail(key, "a whole number");
    }
  }
}

void OptionReader::Read(const std::string& key, bool* value) {
  if (const std::optional<YAML::Node> node = Find(key)) {
    try {
      *value = node->as<bool>();
    } catch (const YAML::Exception&) {
      Fail(key, "true or false");
    }
  }
}

void OptionReader::Read(const std::string& key, std::string* value) {
  if (const std::optional<YAML::Node> node = Find(key)) {
    if (!node->IsScalar()) Fail(key, "a string");
    *value = node->as<std::string>();
  }
}

void OptionReader::RejectUnknownKeys() const {
  if (!node_.IsMap()) return;
  std::string unknown;
  for (const auto& entry : node_) {
    const std::string key = entry.first.as<std::string>();
    if (!known_.count(key)) unknown += (unknown.empty() ? "" : ", ") + key;
  }
  if (!unknown.empty()) {
    std::string accepted;
    for (const std::string& key : known_) accepted += (accepted.empty() ? "" : ", ") + key;
    throw FileError(
        file_.source(), node_.Mark().line + 1,
        "unknown key(s) in '" + section_ + "': " + unknown + " (accepted: " + accepted + ")");
  }
}

}  // namespace stereo_fabmap_slam::io
