#include "parameter_reader.h"

#include <stdexcept>
#include <vector>

namespace stereo_fabmap_slam::ros_parameters {

RosParameterReader::RosParameterReader(const ros::NodeHandle& node, const std::string& section)
    : node_(node), section_(section) {}

template <typename T>
void RosParameterReader::Get(const std::string& key, T* value, const char* expected) {
  visited_.insert(key);
  const std::string name = section_ + "/" + key;
  if (!node_.hasParam(name)) return;
  if (!node_.getParam(name, *value)) {
    throw std::invalid_argument("parameter " + node_.resolveName(name) + " must be " + expected);
  }
}

void RosParameterReader::Visit(const std::string& key, double* value) {
  // Accept integers for real-valued fields (YAML "2" for 2.0).
  visited_.insert(key);
  const std::string name = section_ + "/" + key;
  int whole = 0;
  if (node_.hasParam(name) && !node_.getParam(name, *value) && node_.getParam(name, whole)) {
    *value = whole;
    return;
  }
  Get(key, value, "a number");
}

void RosParameterReader::RejectUnknownKeys() const {
  std::vector<std::string> names;
  if (!node_.getParamNames(names)) return;  // no master to ask: nothing was read from it either
  const std::string prefix = node_.resolveName(section_) + "/";
  std::string unknown;
  for (const std::string& name : names) {
    if (name.rfind(prefix, 0) != 0) continue;
    const std::string key = name.substr(prefix.size());
    if (!visited_.count(key)) unknown += (unknown.empty() ? "" : ", ") + name;
  }
  if (unknown.empty()) return;
  std::string accepted;
  for (const std::string& key : visited_) accepted += (accepted.empty() ? "" : ", ") + key;
  throw std::invalid_argument("unknown parameter(s) " + unknown + " (accepted in '" + section_ +
                              "': " + accepted + ")");
}

void RejectUnknownParameters(const ros::NodeHandle& private_node,
                             const std::set<std::string>& accepted) {
  std::vector<std::string> names;
  if (!private_node.getParamNames(names)) return;  // no master: nothing was read from it either
  const std::string prefix = private_node.getNamespace() + "/";
  std::string unknown;
  for (const std::string& name : names) {
    if (name.rfind(prefix, 0) != 0) continue;
    const std::string key = name.substr(prefix.size());
    // Keys of sections ("features/max_features") are the sections' readers' to check.
    if (key.find('/') == std::string::npos && !accepted.count(key)) {
      unknown += (unknown.empty() ? "" : ", ") + name;
    }
  }
  if (unknown.empty()) return;
  std::string names_accepted;
  for (const std::string& key : accepted) {
    names_accepted += (names_accepted.empty() ? "" : ", ") + key;
  }
  throw std::invalid_argument("unknown parameter(s) " + unknown +
                              " (accepted outside sections: " + names_accepted + ")");
}

void RosParameterReader::Visit(const std::string& key, int* value) {
  Get(key, value, "a whole number");
}
void RosParameterReader::Visit(const std::string& key, bool* value) {
  Get(key, value, "true or false");
}
void RosParameterReader::Visit(const std::string& key, std::string* value) {
  Get(key, value, "a string");
}

}  // namespace stereo_fabmap_slam::ros_parameters
