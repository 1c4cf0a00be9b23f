#pragma once

#include <optional>
#include <ostream>
#include <set>
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
