#pragma once

#include <string>
#include <vector>

#include <yaml-cpp/yaml.h>

namespace stereo_fabmap_slam::io {

// A YAML document and where it came from, so that every error can name the file and line.
// Accepts OpenCV's "%YAML:1.0" first line (EuRoC's sensor.yaml files have it or not), which
// YAML parsers otherwise refuse as a malformed directive.
class YamlFile {
 public:
  static YamlFile Load(const std::string& path);
  static YamlFile Parse(const std::string& text, const std::string& source_name);

  const YAML::Node& root() const { return root_; }
  const std::string& source() const { return source_; }

  // Typed access to a child of `node`; throws InputError "source:line: key ...".
  const YAML::Node Child(const YAML::Node& node, const std::string& key) const;
  bool Has(const YAML::Node& node, const std::string& key) const;
  double Number(const YAML::Node& node, const std::string& key) const;
  std::string String(const YAML::Node& node, const std::string& key) const;
  // A sequence of numbers; expected_size < 0 accepts any length.
  std::vector<double> Numbers(const YAML::Node& node, const std::string& key,
                              int expected_size = -1) const;

 private:
  YamlFile(YAML::Node root, std::string source)
      : root_(std::move(root)), source_(std::move(source)) {}

  YAML::Node root_;
  std::string source_;
};

}  // namespace stereo_fabmap_slam::io
