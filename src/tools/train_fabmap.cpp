// Learns a FAB-MAP vocabulary and Chow-Liu tree from images: folders of photos and/or EuRoC ASL
// sequences, with the odometry's detector and descriptor.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <exception>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include <opencv2/imgcodecs.hpp>

#include "command_line.h"
#include "image_sources.h"
#include "stereo_fabmap_slam/datasets/euroc_sequence.h"
#include "stereo_fabmap_slam/io/options_file.h"
#include "stereo_fabmap_slam/place_recognition/chow_liu_tree.h"
#include "stereo_fabmap_slam/place_recognition/detector_model.h"
#include "stereo_fabmap_slam/place_recognition/image_describer.h"
#include "stereo_fabmap_slam/place_recognition/place_database.h"
#include "stereo_fabmap_slam/place_recognition/place_recognition_options.h"
#include "stereo_fabmap_slam/place_recognition/vocabulary.h"

namespace {

using namespace stereo_fabmap_slam;  // NOLINT: a tool's main file
namespace fs = std::filesystem;

constexpr char kUsage[] =
    "usage: train_fabmap --output DIR [--config FILE] [--fabmap-config FILE] [--every N]\n"
    "                    [--branching B] [--depth D] SOURCE [SOURCE ...]\n"
    "SOURCE: a folder of images (*.png, *.jpg) or a EuRoC ASL sequence (left images); of each,\n"
    "every N-th image (--every) is a training place, so that training views are distinct.\n"
    "Features: the detector and descriptor of --config (default config/euroc.yaml) with the\n"
    "selection, vocabulary size and spacing of --fabmap-config (default config/fabmap.yaml);\n"
    "the flags override the latter. Writes DIR/vocabulary.bin (branching^depth words at most),\n"
    "DIR/chow_liu_tree.bin, DIR/training_places.bin and DIR/detector_model.yaml (p(z|e) and\n"
    "p(z|not e) estimated from neighbouring views of the sequences: at least one is needed).\n";

bool IsSequence(const std::string& source) {
  return fs::is_directory(source + "/mav0") || fs::is_directory(source + "/cam0");
}

}  // namespace

int main(int argc, char** argv) {
  std::optional<tools::CommandLine> args;
  try {
    args.emplace(
        argc, argv,
        std::set<std::string>{"output", "config", "fabmap-config", "every", "branching", "depth"},
        std::set<std::string>{"help"});
    if (args->Flag("help")) {
      std::fputs(kUsage, stdout);
      return 0;
    }
    if (!args->Value("output") || args->positional().empty())
      throw std::invalid_argument("--output and a SOURCE are required");
  } catch (const std::invalid_argument& error) {
    std::fprintf(stderr, "train_fabmap: %s\n%s", error.what(), kUsage);
    return 2;
  }
  try {
    const std::string output = *args->Value("output");
    const std::string config = args->ValueOr("config", STEREO_FABMAP_SLAM_CONFIG_DIR "/euroc.yaml");
    place_recognition::PlaceRecognitionOptions options =
        place_recognition::LoadPlaceRecognitionOptions(
            args->ValueOr("fabmap-config", STEREO_FABMAP_SLAM_CONFIG_DIR "/fabmap.yaml"),
            io::OptionsFile::Load(config).Read<features::FeatureOptions>());
    const int spacing = static_cast<int>(args->NumberOr("every", options.training.spacing));
    place_recognition::VocabularyOptions& vocabulary_options = options.vocabulary;
    vocabulary_options.branching =
        static_cast<int>(args->NumberOr("branching", vocabulary_options.branching));
    vocabulary_options.depth = static_cast<int>(args->NumberOr("depth", vocabulary_options.depth));
    if (spacing < 1) throw std::runtime_error("--every must be >= 1");
    vocabulary_options.Validate();
    std::vector<std::string> images;
    // Per source that is a sequence: the indices of its images, in order. Neighbours (`spacing`
    // frames apart, a keyframe's distance) show one place: the detector model's evidence.
    std::vector<std::vector<std::size_t>> sequences;
    for (const std::string& source : args->positional()) {
      const std::vector<tools::ImageSource> found = tools::ListImages(source, spacing);
      std::printf("%s: %zu training images\n", source.c_str(), found.size());
      if (IsSequence(source)) sequences.emplace_back();
      for (const tools::ImageSource& image : found) {
        if (IsSequence(source)) sequences.back().push_back(images.size());
        images.push_back(image.path);
      }
    }
    if (images.size() < 2) throw std::runtime_error("need at least two training images");

    // Descriptors of every image, with the odometry's features.
    place_recognition::ImageDescriber describer(options.features);
    std::vector<cv::Mat> per_image;
    cv::Mat all;
    for (std::size_t i = 0; i < images.size(); ++i) {
      const cv::Mat image = cv::imread(images[i], cv::IMREAD_GRAYSCALE);
      if (image.empty()) throw std::runtime_error(images[i] + ": cannot read image");
      per_image.push_back(describer.Describe(image));
      all.push_back(per_image.back());
      if ((i + 1) % 50 == 0 || i + 1 == images.size()) {
        std::fprintf(stderr, "  described %zu / %zu images (%d descriptors)\n", i + 1,
                     images.size(), all.rows);
      }
    }
    std::fprintf(
        stderr, "  clustering %d descriptors into up to %d words...\n", all.rows,
        static_cast<int>(std::pow(vocabulary_options.branching, vocabulary_options.depth)));
    const place_recognition::Vocabulary vocabulary =
        place_recognition::Vocabulary::Train(all, vocabulary_options);
    std::vector<std::vector<int>> word_sets;
    place_recognition::PlaceDatabase training_places(vocabulary.size());
    for (const cv::Mat& descriptors : per_image) {
      word_sets.push_back(vocabulary.WordSet(descriptors));
      training_places.AddPlace(word_sets.back());
    }
    std::fprintf(stderr, "  learning the Chow-Liu tree over %d words from %zu images...\n",
                 vocabulary.size(), word_sets.size());
    const place_recognition::ChowLiuTree tree =
        place_recognition::ChowLiuTree::Train(word_sets, vocabulary.size());
    std::vector<std::vector<std::vector<int>>> sequence_views;
    for (const std::vector<std::size_t>& sequence : sequences) {
      sequence_views.emplace_back();
      for (const std::size_t i : sequence) sequence_views.back().push_back(word_sets[i]);
    }
    const place_recognition::DetectorModel detector =
        place_recognition::EstimateDetectorModel(sequence_views, vocabulary.size());
    std::printf(
        "detector model from %d triples of neighbouring views: p(z|e) %.3f, "
        "p(z|not e) %.5f\n",
        detector.triples, detector.p_z_given_e, detector.p_z_given_not_e);
    fs::create_directories(output);
    vocabulary.Save(output + "/vocabulary.bin");
    place_recognition::SaveDetectorModel(detector, output + "/detector_model.yaml");
    tree.Save(output + "/chow_liu_tree.bin");
    training_places.Save(output + "/training_places.bin");
    std::printf("wrote %s: %d words, Chow-Liu tree from %zu images\n", output.c_str(),
                vocabulary.size(), word_sets.size());
  } catch (const std::exception& error) {
    std::fprintf(stderr, "train_fabmap: %s\n", error.what());
    return 1;
  }
  return 0;
}
