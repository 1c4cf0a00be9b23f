#include "parameter_reader.h"

#include <stdexcept>

namespace stereo_fabmap_slam::ros_parameters {

RosParameterReader::RosParameterReader(const ros::NodeHandle& node, const std::string& section)
    : node_(node), section_(section) {}

template <typename T>
void RosParameterReader::Get(const std::string& key, T* value, const char* expected) {
  const std::string name = section_ + "/" + key;
  if (!node_.hasParam(name)) return;
  if (!node_.getParam(name, *value)) {
    throw std::invalid_argument("parameter " + node_.resolveName(name) + " must be " + expected);
  }
}

void RosParameterReader::Visit(const std::string& key, double* value) {
  // Accept integers for real-valued fields (YAML "2" for 2.0).
  const std::string name = section_ + "/" + key;
  int whole = 0;
  if (node_.hasParam(name) && !node_.getParam(name, *value) && node_.getParam(name, whole)) {
    *value = whole;
    return;
  }
  Get(key, value, "a number");
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
