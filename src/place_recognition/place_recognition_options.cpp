#include "stereo_fabmap_slam/place_recognition/place_recognition_options.h"

#include <filesystem>
#include <stdexcept>

#include "stereo_fabmap_slam/io/csv_reader.h"
#include "stereo_fabmap_slam/io/option_reader.h"

namespace stereo_fabmap_slam::place_recognition {

void PlaceRecognitionOptions::Validate() const {
  features.Validate();
  vocabulary.Validate();
  fabmap.Validate();
  if (training_spacing < 1) throw std::invalid_argument("training.spacing must be >= 1");
}

PlaceRecognitionOptions LoadPlaceRecognitionOptions(
    const std::string& path, const features::FeatureOptions& odometry_features) {
  const io::YamlFile file = io::YamlFile::Load(path);
  PlaceRecognitionOptions options;
  options.features = odometry_features;
  const auto section = [&](const char* name, auto& target) {
    const YAML::Node node = file.Has(file.root(), name) ? file.root()[name] : YAML::Node();
    io::YamlOptionReader reader(file, node, name);
    target.Visit(reader);
    reader.RejectUnknownKeys();
  };
  section("features", options.features);
  section("vocabulary", options.vocabulary);
  section("fabmap", options.fabmap);
  struct Training {
    int* spacing;
    void Visit(io::OptionVisitor& visitor) { visitor.Visit("spacing", spacing); }
  } training{&options.training_spacing};
  section("training", training);
  for (const auto& entry : file.root()) {
    const std::string key = entry.first.as<std::string>();
    if (key != "vocabulary_directory" && key != "features" && key != "vocabulary" &&
        key != "fabmap" && key != "training") {
      throw io::FileError(path, entry.first.Mark().line + 1, "unknown section '" + key + "'");
    }
  }
  if (file.Has(file.root(), "vocabulary_directory")) {
    const std::filesystem::path directory = file.String(file.root(), "vocabulary_directory");
    options.vocabulary_directory =
        (directory.is_absolute() ? directory
                                 : std::filesystem::path(path).parent_path() / directory)
            .lexically_normal()
            .string();
  }
  try {
    options.Validate();
  } catch (const std::invalid_argument& error) {
    throw io::FileError(path, 0, error.what());
  }
  return options;
}

}  // namespace stereo_fabmap_slam::place_recognition
