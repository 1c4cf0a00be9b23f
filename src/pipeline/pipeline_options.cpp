#include "stereo_fabmap_slam/pipeline/pipeline_options.h"

#include <filesystem>
#include <set>
#include <stdexcept>

#include "stereo_fabmap_slam/io/csv_reader.h"

namespace stereo_fabmap_slam::pipeline {
namespace {

void LoadInto(const std::string& path, PipelineOptions* options, int depth) {
  if (depth > 8) throw io::FileError(path, 0, "include chain too deep (a cycle?)");
  const io::YamlFile file = io::YamlFile::Load(path);
  std::set<std::string> known = {"include"};
  if (file.Has(file.root(), "include")) {
    const std::filesystem::path included =
        std::filesystem::path(path).parent_path() / file.String(file.root(), "include");
    LoadInto(included.string(), options, depth + 1);
  }
  options->ForEachSection([&](const std::string& section, auto& section_options) {
    known.insert(section);
    // An absent section keeps every default (yaml-cpp's node for a missing key is unusable).
    const YAML::Node node = file.Has(file.root(), section) ? file.root()[section] : YAML::Node();
    io::YamlOptionReader reader(file, node, section);
    section_options.Visit(reader);
    reader.RejectUnknownKeys();
  });
  for (const auto& entry : file.root()) {
    const std::string key = entry.first.as<std::string>();
    if (!known.count(key)) {
      throw io::FileError(path, entry.first.Mark().line + 1, "unknown section '" + key + "'");
    }
  }
}

}  // namespace

void PipelineOptions::Validate() const {
  rectification.Validate();
  features.Validate();
  stereo.Validate();
  tracker.Validate();
  keyframes.Validate();
  backend.Validate();
}

void PipelineOptions::Print(std::ostream& out) const {
  PipelineOptions copy = *this;  // visiting takes mutable fields; printing changes nothing
  copy.ForEachSection([&](const std::string& section, auto& section_options) {
    io::OptionPrinter printer(out, section);
    section_options.Visit(printer);
  });
}

PipelineOptions LoadPipelineOptions(const std::string& path) {
  PipelineOptions options;
  LoadInto(path, &options, 0);
  try {
    options.Validate();
  } catch (const std::invalid_argument& error) {
    throw io::FileError(path, 0, error.what());
  }
  return options;
}

}  // namespace stereo_fabmap_slam::pipeline
