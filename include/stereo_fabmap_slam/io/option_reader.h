#pragma once

#include <optional>
#include <ostream>
#include <set>
#include <stdexcept>
#include <string>

#include "stereo_fabmap_slam/io/yaml_file.h"

namespace stereo_fabmap_slam::io {

// Every Options struct lists its fields once, in Visit(OptionVisitor&); the visitor decides what
// happens to them: read from YAML (YamlOptionReader), printed (OptionPrinter), or read from ROS
// parameters (in the nodelets).
class OptionVisitor {
 public:
  virtual ~OptionVisitor() = default;
  virtual void Visit(const std::string& key, double* value) = 0;
  virtual void Visit(const std::string& key, int* value) = 0;
  virtual void Visit(const std::string& key, bool* value) = 0;
  virtual void Visit(const std::string& key, std::string* value) = 0;
};

// One value of an enumerated option and its name in configuration files.
template <typename Enum>
struct EnumName {
  Enum value;
  const char* name;
};

// Visits an enumerated field by its name, so that a mode is parsed once when the options are
// read (never compared as a string per query). An unknown name throws std::invalid_argument
// listing the known ones.
template <typename Enum, std::size_t N>
void VisitEnum(OptionVisitor& visitor, const std::string& key, Enum* value,
               const EnumName<Enum> (&names)[N]) {
  std::string name;
  for (const EnumName<Enum>& entry : names) {
    if (entry.value == *value) name = entry.name;
  }
  visitor.Visit(key, &name);
  std::string known;
  for (const EnumName<Enum>& entry : names) {
    if (name == entry.name) {
      *value = entry.value;
      return;
    }
    known += (known.empty() ? "" : ", ") + std::string(entry.name);
  }
  throw std::invalid_argument(key + " '" + name + "' is unknown; available: " + known);
}

// Fills fields from one YAML mapping: every key is optional (the default stays), a key of the
// wrong type is an error naming file and line, and so is a key no field asked for (a typo must
// not silently leave a default in place; call RejectUnknownKeys() after visiting).
class YamlOptionReader : public OptionVisitor {
 public:
  // `node` may be undefined (section absent): then every field keeps its default.
  YamlOptionReader(const YamlFile& file, const YAML::Node& node, std::string section);

  void Visit(const std::string& key, double* value) override;
  void Visit(const std::string& key, int* value) override;
  void Visit(const std::string& key, bool* value) override;
  void Visit(const std::string& key, std::string* value) override;
  // Throws InputError listing the keys of the section that no field asked for.
  void RejectUnknownKeys() const;

 private:
  std::optional<YAML::Node> Find(const std::string& key);
  [[noreturn]] void Fail(const std::string& key, const char* expected) const;

  const YamlFile& file_;
  YAML::Node node_;
  std::string section_;
  std::set<std::string> known_;
};

// Writes "section:\n  key: value" lines, e.g. to print the options in force at start-up.
class OptionPrinter : public OptionVisitor {
 public:
  OptionPrinter(std::ostream& out, const std::string& section);
  void Visit(const std::string& key, double* value) override;
  void Visit(const std::string& key, int* value) override;
  void Visit(const std::string& key, bool* value) override;
  void Visit(const std::string& key, std::string* value) override;

 private:
  std::ostream& out_;
};

}  // namespace stereo_fabmap_slam::io
