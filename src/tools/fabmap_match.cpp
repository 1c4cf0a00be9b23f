// Adds the images of a folder or EuRoC sequence to a FAB-MAP map in order and prints, for each,
// the best earlier place, its posterior and the new-place probability, as CSV.
#include <algorithm>
#include <cstdio>
#include <exception>
#include <filesystem>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include <opencv2/imgcodecs.hpp>

#include "command_line.h"
#include "fabmap_files.h"
#include "image_sources.h"
#include "stereo_fabmap_slam/datasets/euroc_sequence.h"
#include "stereo_fabmap_slam/io/options_file.h"
#include "stereo_fabmap_slam/place_recognition/detector_model.h"
#include "stereo_fabmap_slam/place_recognition/fab_map.h"
#include "stereo_fabmap_slam/place_recognition/image_describer.h"
#include "stereo_fabmap_slam/place_recognition/place_recognition_options.h"
#include "stereo_fabmap_slam/place_recognition/vocabulary.h"

namespace {

using namespace stereo_fabmap_slam;  // NOLINT: a tool's main file
namespace fs = std::filesystem;

constexpr char kUsage[] =
    "usage: fabmap_match [--vocabulary FILE] ASL_OR_IMAGE_DIR [--every N] [--config FILE]\n"
    "                    [--fabmap-config FILE] [--sampling]\n"
    "FILE: a vocabulary.bin from train_fabmap, with chow_liu_tree.bin and training_places.bin\n"
    "beside it (default: the vocabulary_directory of config/fabmap.yaml). Prints\n"
    "CSV: image,timestamp,place,best_place,best_posterior,new_place_probability\n"
    "(place: the place the image was added to or updated; best_place -1 while the map is empty).\n";

}  // namespace

int main(int argc, char** argv) {
  std::optional<tools::CommandLine> args;
  int every = 1;
  try {
    args.emplace(argc, argv,
                 std::set<std::string>{"vocabulary", "every", "config", "fabmap-config"},
                 std::set<std::string>{"sampling", "help"});
    if (args->Flag("help")) {
      std::fputs(kUsage, stdout);
      return 0;
    }
    if (args->positional().size() != 1)
      throw std::invalid_argument("one ASL_OR_IMAGE_DIR is required");
    every = static_cast<int>(args->NumberOr("every", 1));
    if (every < 1) throw std::invalid_argument("--every must be >= 1");
  } catch (const std::invalid_argument& error) {
    std::fprintf(stderr, "fabmap_match: %s\n%s", error.what(), kUsage);
    return 2;
  }
  try {
    place_recognition::PlaceRecognitionOptions options =
        place_recognition::LoadPlaceRecognitionOptions(
            args->ValueOr("fabmap-config", STEREO_FABMAP_SLAM_CONFIG_DIR "/fabmap.yaml"),
            io::OptionsFile::Load(
                args->ValueOr("config", STEREO_FABMAP_SLAM_CONFIG_DIR "/euroc.yaml"))
                .Read<features::FeatureOptions>());
    tools::FabMapFiles files = tools::LoadFabMapFiles(
        args->ValueOr("vocabulary", options.vocabulary_directory + "/vocabulary.bin"));
    const place_recognition::Vocabulary& vocabulary = files.vocabulary;
    place_recognition::FabMapOptions fabmap_options =
        place_recognition::ResolveDetectorModel(options.fabmap, files.directory);
    if (args->Flag("sampling"))
      fabmap_options.new_place_model = place_recognition::NewPlaceModel::kSampling;
    place_recognition::FabMap fabmap(std::move(files.tree), fabmap_options,
                                     std::move(files.training_places));
    place_recognition::ImageDescriber describer(options.features);
    // Listed first: a source without images is an error, without a CSV header on stdout.
    const std::vector<tools::ImageSource> images = tools::ListImages(args->positional()[0], every);
    std::printf("image,timestamp,place,best_place,best_posterior,new_place_probability\n");
    for (const tools::ImageSource& image : images) {
      const cv::Mat pixels = cv::imread(image.path, cv::IMREAD_GRAYSCALE);
      if (pixels.empty()) throw std::runtime_error(image.path + ": cannot read image");
      int place = -1;
      const place_recognition::FabMapResult result =
          fabmap.Add(vocabulary.WordSet(describer.Describe(pixels)), &place);
      std::printf("%s,%.9f,%d,%d,%.6f,%.6f\n", fs::path(image.path).filename().c_str(),
                  image.timestamp, place, result.best,
                  result.best >= 0 ? result.posterior[static_cast<std::size_t>(result.best)] : 0.0,
                  result.new_place);
    }
  } catch (const std::exception& error) {
    std::fprintf(stderr, "fabmap_match: %s\n", error.what());
    return 1;
  }
  return 0;
}
