#include "stereo_fabmap_slam/io/yaml_file.h"

#include <fstream>
#include <sstream>

#include "stereo_fabmap_slam/io/input_error.h"

namespace stereo_fabmap_slam::io {
namespace {

// Line of a node for messages: yaml-cpp counts from 0, editors from 1.
std::size_t LineOf(const YAML::Node& node) {
  const YAML::Mark mark = node.Mark();
  return mark.line >= 0 ? static_cast<std::size_t>(mark.line) + 1 : 0;
}

}  // namespace

YamlFile YamlFile::Load(const std::string& path) {
  std::ifstream file(path);
  if (!file) throw FileError(path, 0, "cannot open file");
  std::stringstream text;
  text << file.rdbuf();
  return Parse(text.str(), path);
}

YamlFile YamlFile::Parse(const std::string& text, const std::string& source_name) {
  std::string document = text;
  if (document.rfind("%YAML:", 0) == 0) {
    // Blank the OpenCV header but keep the line so that line numbers stay true.
    document.replace(0, document.find('\n'), "");
  }
  try {
    YAML::Node root = YAML::Load(document);
    if (!root.IsMap()) throw FileError(source_name, 0, "expected a YAML mapping at the top level");
    return YamlFile(root, source_name);
  } catch (const YAML::Exception& error) {
    throw FileError(source_name, static_cast<std::size_t>(error.mark.line + 1), error.msg);
  }
}

bool YamlFile::Has(const YAML::Node& node, const std::string& key) const {
  return node.IsMap() && node[key].IsDefined();
}

const YAML::Node YamlFile::Child(const YAML::Node& node, const std::string& key) const {
  if (!Has(node, key)) throw FileError(source_, LineOf(node), "missing key '" + key + "'");
  return node[key];
}

double YamlFile::Number(const YAML::Node& node, const std::string& key) const {
  const YAML::Node child = Child(node, key);
  try {
    return child.as<double>();
  } catch (const YAML::Exception&) {
    throw FileError(source_, LineOf(child), "'" + key + "' must be a number");
  }
}

std::string YamlFile::String(const YAML::Node& node, const std::string& key) const {
  const YAML::Node child = Child(node, key);
  if (!child.IsScalar()) throw FileError(source_, LineOf(child), "'" + key + "' must be a string");
  return child.as<std::string>();
}

std::vector<double> YamlFile::Numbers(const YAML::Node& node, const std::string& key,
                                      int expected_size) const {
  const YAML::Node child = Child(node, key);
  std::vector<double> values;
  try {
    values = child.as<std::vector<double>>();
  } catch (const YAML::Exception&) {
    throw FileError(source_, LineOf(child), "'" + key + "' must be a list of numbers");
  }
  if (expected_size >= 0 && values.size() != static_cast<std::size_t>(expected_size)) {
    throw FileError(source_, LineOf(child),
                    "'" + key + "' must have " + std::to_string(expected_size) +
                        " numbers, found " + std::to_string(values.size()));
  }
  return values;
}

}  // namespace stereo_fabmap_slam::io
