#include "command_line.h"

#include <cctype>
#include <cstdlib>
#include <stdexcept>

namespace stereo_fabmap_slam::tools {

CommandLine::CommandLine(int argc, char** argv, const std::set<std::string>& value_options,
                         const std::set<std::string>& flags) {
  for (int i = 1; i < argc; ++i) {
    const std::string argument = argv[i];
    if (argument == "-h" && flags.count("help")) {
      flags_.insert("help");
      continue;
    }
    // A single dash with a letter is an option nobody offers ("-o"), not a file; a lone "-" or
    // a negative number stays positional.
    if (argument.size() >= 2 && argument[0] == '-' && argument[1] != '-' &&
        !std::isdigit(static_cast<unsigned char>(argument[1])) && argument[1] != '.') {
      throw std::invalid_argument("unknown option " + argument);
    }
    if (argument.rfind("--", 0) != 0 || argument.size() == 2) {
      positional_.push_back(argument);
      continue;
    }
    const std::size_t equals = argument.find('=');
    const std::string name =
        argument.substr(2, equals == std::string::npos ? std::string::npos : equals - 2);
    if (flags.count(name)) {
      if (equals != std::string::npos) throw std::invalid_argument("--" + name + " takes no value");
      flags_.insert(name);
    } else if (value_options.count(name)) {
      if (equals != std::string::npos) {
        values_[name] = argument.substr(equals + 1);
      } else if (i + 1 < argc) {
        values_[name] = argv[++i];
      } else {
        throw std::invalid_argument("--" + name + " needs a value");
      }
    } else {
      throw std::invalid_argument("unknown option --" + name);
    }
  }
}

std::optional<std::string> CommandLine::Value(const std::string& name) const {
  const auto found = values_.find(name);
  if (found == values_.end()) return std::nullopt;
  return found->second;
}

std::string CommandLine::ValueOr(const std::string& name, const std::string& fallback) const {
  return Value(name).value_or(fallback);
}

double CommandLine::NumberOr(const std::string& name, double fallback) const {
  const std::optional<std::string> text = Value(name);
  if (!text) return fallback;
  char* end = nullptr;
  const double value = std::strtod(text->c_str(), &end);
  if (text->empty() || *end != '\0') {
    throw std::invalid_argument("--" + name + " must be a number, got '" + *text + "'");
  }
  return value;
}

}  // namespace stereo_fabmap_slam::tools
