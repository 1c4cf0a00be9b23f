#pragma once

#include <map>
#include <optional>
#include <set>
#include <string>
#include <vector>

namespace stereo_fabmap_slam::tools {

// GNU-style arguments: "--name value", "--name=value", "--flag", and positional arguments;
// "-h" is "--help" where the tool offers it. Unknown options (also "-x") and missing values
// throw std::invalid_argument with a readable message.
class CommandLine {
 public:
  CommandLine(int argc, char** argv, const std::set<std::string>& value_options,
              const std::set<std::string>& flags);

  std::optional<std::string> Value(const std::string& name) const;
  std::string ValueOr(const std::string& name, const std::string& fallback) const;
  double NumberOr(const std::string& name, double fallback) const;
  bool Flag(const std::string& name) const { return flags_.count(name) > 0; }
  const std::vector<std::string>& positional() const { return positional_; }

 private:
  std::map<std::string, std::string> values_;
  std::set<std::string> flags_;
  std::vector<std::string> positional_;
};

}  // namespace stereo_fabmap_slam::tools
