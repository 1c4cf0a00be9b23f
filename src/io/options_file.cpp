#include "stereo_fabmap_slam/io/options_file.h"

#include <filesystem>
#include <string>

namespace stereo_fabmap_slam::io {
namespace {

constexpr int kMaxIncludeDepth = 8;

void LoadChain(const std::string& path, int depth, std::vector<YamlFile>* layers) {
  if (depth > kMaxIncludeDepth) throw FileError(path, 0, "include chain too deep (a cycle?)");
  YamlFile file = YamlFile::Load(path);
  if (file.Has(file.root(), "include")) {
    const std::filesystem::path included =
        std::filesystem::path(path).parent_path() / file.String(file.root(), "include");
    try {
      LoadChain(included.string(), depth + 1, layers);
    } catch (const InputError& error) {
      // Say which file asked for it, and where: the error alone names only the included one.
      throw InputError(std::string(error.what()) + "\n  included from " + path + ":" +
                       std::to_string(file.root()["include"].Mark().line + 1));
    }
  }
  layers->push_back(std::move(file));
}

}  // namespace

OptionsFile OptionsFile::Load(const std::string& path) {
  OptionsFile file;
  LoadChain(path, 0, &file.layers_);
  return file;
}

void OptionsFile::ReadSection(const std::string& section,
                              const std::function<void(OptionVisitor&)>& visit) const {
  for (const YamlFile& layer : layers_) {
    // yaml-cpp's node for a missing key is unusable: an absent section reads as undefined.
    const YAML::Node node = layer.Has(layer.root(), section) ? layer.root()[section] : YAML::Node();
    YamlOptionReader reader(layer, node, section);
    visit(reader);
    reader.RejectUnknownKeys();
  }
}

void OptionsFile::RejectUnknownSections(const std::set<std::string>& known) const {
  for (const YamlFile& layer : layers_) {
    for (const auto& entry : layer.root()) {
      const std::string key = entry.first.as<std::string>();
      if (key != "include" && !known.count(key)) {
        throw FileError(layer.source(), entry.first.Mark().line + 1,
                        "unknown section '" + key + "'");
      }
    }
  }
}

std::optional<std::string> OptionsFile::Path(const std::string& key) const {
  for (auto layer = layers_.rbegin(); layer != layers_.rend(); ++layer) {
    if (!layer->Has(layer->root(), key)) continue;
    const std::filesystem::path value = layer->String(layer->root(), key);
    return (value.is_absolute() ? value
                                : std::filesystem::path(layer->source()).parent_path() / value)
        .lexically_normal()
        .string();
  }
  return std::nullopt;
}

}  // namespace stereo_fabmap_slam::io
