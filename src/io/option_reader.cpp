#include "stereo_fabmap_slam/io/option_reader.h"

#include "stereo_fabmap_slam/io/input_error.h"

namespace stereo_fabmap_slam::io {

YamlOptionReader::YamlOptionReader(const YamlFile& file, const YAML::Node& node,
                                   std::string section)
    : file_(file), node_(node), section_(std::move(section)) {
  if (node_.IsDefined() && !node_.IsNull() && !node_.IsMap()) {
    throw FileError(file_.source(), node_.Mark().line + 1, "'" + section_ + "' must be a mapping");
  }
}

std::optional<YAML::Node> YamlOptionReader::Find(const std::string& key) {
  known_.insert(key);
  if (!node_.IsMap() || !node_[key].IsDefined()) return std::nullopt;
  return node_[key];
}

void YamlOptionReader::Fail(const std::string& key, const char* expected) const {
  throw FileError(file_.source(), node_[key].Mark().line + 1,
                  section_ + "." + key + " must be " + expected);
}

void YamlOptionReader::Visit(const std::string& key, double* value) {
  if (const std::optional<YAML::Node> node = Find(key)) {
    try {
      *value = node->as<double>();
    } catch (const YAML::Exception&) {
      Fail(key, "a number");
    }
  }
}

void YamlOptionReader::Visit(const std::string& key, int* value) {
  if (const std::optional<YAML::Node> node = Find(key)) {
    try {
      *value = node->as<int>();
    } catch (const YAML::Exception&) {
      Fail(key, "a whole number");
    }
  }
}

void YamlOptionReader::Visit(const std::string& key, bool* value) {
  if (const std::optional<YAML::Node> node = Find(key)) {
    try {
      *value = node->as<bool>();
    } catch (const YAML::Exception&) {
      Fail(key, "true or false");
    }
  }
}

void YamlOptionReader::Visit(const std::string& key, std::string* value) {
  if (const std::optional<YAML::Node> node = Find(key)) {
    if (!node->IsScalar()) Fail(key, "a string");
    *value = node->as<std::string>();
  }
}

void YamlOptionReader::RejectUnknownKeys() const {
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

OptionPrinter::OptionPrinter(std::ostream& out, const std::string& section) : out_(out) {
  out_ << section << ":\n";
}

void OptionPrinter::Visit(const std::string& key, double* value) {
  out_ << "  " << key << ": " << *value << "\n";
}

void OptionPrinter::Visit(const std::string& key, int* value) {
  out_ << "  " << key << ": " << *value << "\n";
}

void OptionPrinter::Visit(const std::string& key, bool* value) {
  out_ << "  " << key << ": " << (*value ? "true" : "false") << "\n";
}

void OptionPrinter::Visit(const std::string& key, std::string* value) {
  out_ << "  " << key << ": " << *value << "\n";
}

}  // namespace stereo_fabmap_slam::io
