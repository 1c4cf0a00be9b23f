#pragma once

// Options of the core library's modules from ROS parameters, for the nodelets.

#include <set>
#include <sstream>
#include <string>

#include <ros/node_handle.h>

#include "stereo_fabmap_slam/io/option_reader.h"
#include "stereo_fabmap_slam/io/options_file.h"

namespace stereo_fabmap_slam::ros_parameters {

// Fills Options fields from ROS parameters "<namespace>/<section>/<key>" (e.g. the private
// "~features/max_features" after `rosparam load config/euroc.yaml`); absent parameters keep the
// default, a parameter of the wrong type throws std::invalid_argument naming it. Like a YAML
// section, a key the Options do not have is refused (RejectUnknownKeys): a misspelt
// "~features/max_featurs" must not be silently ignored.
class RosParameterReader : public io::OptionVisitor {
 public:
  RosParameterReader(const ros::NodeHandle& node, const std::string& section);
  void Visit(const std::string& key, double* value) override;
  void Visit(const std::string& key, int* value) override;
  void Visit(const std::string& key, bool* value) override;
  void Visit(const std::string& key, std::string* value) override;
  // After Visit: throws std::invalid_argument naming the parameters under "<section>/" that
  // no visited field has, with the accepted keys.
  void RejectUnknownKeys() const;

 private:
  template <typename T>
  void Get(const std::string& key, T* value, const char* expected);

  ros::NodeHandle node_;
  std::string section_;
  std::set<std::string> visited_;
};

// Throws std::invalid_argument naming every private parameter of `private_node` outside the
// sections (a name without "/") that is not one of `accepted`, with the accepted names: a
// misspelt "~tf_rat" must not be silently ignored any more than "~features/max_featurs".
void RejectUnknownParameters(const ros::NodeHandle& private_node,
                             const std::set<std::string>& accepted);

// One module's options for a nodelet: its section of the YAML file in ~config_file (if set),
// then private parameters "~<section>/<key>" over it, validated. Throws std::exception naming
// the bad value; the nodelet reports it and refuses to start.
template <typename Options>
Options ReadModuleOptions(const ros::NodeHandle& private_node, Options options = Options()) {
  std::string config_file;
  if (private_node.getParam("config_file", config_file) && !config_file.empty()) {
    options = io::OptionsFile::Load(config_file).Read(options);
  }
  RosParameterReader reader(private_node, Options::kSection);
  options.Visit(reader);
  reader.RejectUnknownKeys();
  options.Validate();
  return options;
}

// The options as YAML, for the start-up log.
template <typename Options>
std::string PrintedOptions(const Options& options) {
  std::ostringstream printed;
  io::PrintOptions(options, printed);
  return printed.str();
}

}  // namespace stereo_fabmap_slam::ros_parameters
