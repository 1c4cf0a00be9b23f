#pragma once

#include <functional>
#include <optional>
#include <ostream>
#include <set>
#include <stdexcept>
#include <string>
#include <vector>

#include "stereo_fabmap_slam/io/input_error.h"
#include "stereo_fabmap_slam/io/option_reader.h"
#include "stereo_fabmap_slam/io/yaml_file.h"

namespace stereo_fabmap_slam::io {

// A configuration file of sections, one per module's Options struct. Every Options struct names
// its section (`static constexpr char kSection[]`) and lists its fields in Visit(), so one
// reader serves them all:
//
//   const io::OptionsFile file = io::OptionsFile::Load("config/euroc.yaml");
//   odometry::TrackerOptions tracker = file.Read<odometry::TrackerOptions>();
//
// A file may start with "include: other.yaml" (relative to itself): that file is read first and
// this one overrides it, so that presets (keyframes_more.yaml) are a few lines over euroc.yaml.
class OptionsFile {
 public:
  // Throws InputError naming the file (and line) of a syntax error or a broken include.
  static OptionsFile Load(const std::string& path);

  // The section of `Options` from every file of the include chain: an absent section keeps the
  // defaults; an unknown key, a value of the wrong type or one that Validate() refuses throws
  // InputError naming the file (and line).
  template <typename Options>
  Options Read(Options options = Options()) const {
    ReadSection(Options::kSection, [&](OptionVisitor& visitor) { options.Visit(visitor); });
    try {
      options.Validate();
    } catch (const std::invalid_argument& error) {
      throw FileError(path(), 0, error.what());
    }
    return options;
  }

  // Throws InputError naming the first top-level key of any file in the chain that is not in
  // `known` ("include" is always known): for tools that read every section of a file.
  void RejectUnknownSections(const std::set<std::string>& known) const;
  // A top-level string that names a file or folder, made absolute relative to the file that
  // sets it (the last in the chain that does); nullopt if none does.
  std::optional<std::string> Path(const std::string& key) const;
  const std::string& path() const { return layers_.back().source(); }

 private:
  void ReadSection(const std::string& section,
                   const std::function<void(OptionVisitor&)>& visit) const;

  std::vector<YamlFile> layers_;  // the include chain, the included (base) file first
};

// Prints one Options struct as its YAML section ("section:\n  key: value").
template <typename Options>
void PrintOptions(Options options, std::ostream& out) {
  OptionPrinter printer(out, Options::kSection);
  options.Visit(printer);
}

}  // namespace stereo_fabmap_slam::io
