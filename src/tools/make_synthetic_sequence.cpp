// Renders a synthetic stereo sequence with exact ground truth into EuRoC's ASL layout, plus a bag.
#include <cstdio>
#include <exception>
#include <optional>
#include <string>

#include "command_line.h"
#include "euroc_bag_writer.h"
#include "stereo_fabmap_slam/datasets/euroc_sequence.h"
#include "stereo_fabmap_slam/datasets/synthetic_sequence.h"

namespace {

using namespace stereo_fabmap_slam;  // NOLINT: a tool's main file

constexpr char kUsage[] =
    "usage: make_synthetic_sequence --output DIR [--scene hall|office] [--seed N]\n"
    "                               [--route loop|figure8|kidnap] [--seconds S] [--noise SIGMA]\n"
    "                               [--resolution WxH] [--no-distortion] [--exposure-changes]\n"
    "                               [--auto-exposure|--no-auto-exposure] [--motion-blur]\n"
    "                               [--photos FOLDER] [--no-bag]\n"
    "Renders a stereo camera (EuRoC-like: 752x480, 20 Hz, 0.11 m baseline) moving through a\n"
    "rendered world into DIR in EuRoC's ASL layout (mav0/cam0, mav0/cam1, ground truth at\n"
    "200 Hz) and writes DIR/sequence.bag (/cam0/image_raw, /cam1/image_raw, /ground_truth).\n"
    "  --scene hall     a hall papered with photographs (from --photos, default opencv-doc's)\n"
    "  --scene office   an office floor (30 x 15 m): corridors of plain walls and identical\n"
    "                   doors around two blocks, a lobby and a kitchen corner; auto exposure on.\n"
    "                   loop: once around the outer corridors (80 s a lap); figure8: twice up\n"
    "                   the middle corridor, around each block (108 s)\n"
    "  --resolution     another image size with the same field of view (e.g. 512x384)\n"
    "Defaults: hall, seed 1, route loop, 40 s, noise 2 grey levels, EuRoC lens distortion.\n";

}  // namespace

int main(int argc, char** argv) {
  std::optional<tools::CommandLine> args;
  datasets::SyntheticSequenceOptions options;
  std::string out;
  try {
    args.emplace(argc, argv,
                 std::set<std::string>{"output", "scene", "seed", "route", "seconds", "noise",
                                       "resolution", "photos"},
                 std::set<std::string>{"no-distortion", "exposure-changes", "auto-exposure",
                                       "no-auto-exposure", "motion-blur", "no-bag", "help"});
    if (args->Flag("help")) {
      std::fputs(kUsage, stdout);
      return 0;
    }
    if (!args->Value("output") || !args->positional().empty())
      throw std::invalid_argument("--output DIR is required");
    out = *args->Value("output");
    options = datasets::SyntheticSequenceOptions::ForScene(args->ValueOr("scene", "hall"));
    const double seed = args->NumberOr("seed", 1);
    if (seed < 0 || seed != static_cast<double>(static_cast<std::uint64_t>(seed))) {
      throw std::invalid_argument("--seed must be a whole number >= 0");
    }
    options.seed = static_cast<std::uint64_t>(seed);
    options.route = args->ValueOr("route", options.route);
    options.seconds = args->NumberOr("seconds", options.seconds);
    options.noise_sigma = args->NumberOr("noise", options.noise_sigma);
    options.photo_folder = args->ValueOr("photos", options.photo_folder);
    options.distortion = !args->Flag("no-distortion");
    options.exposure_changes = args->Flag("exposure-changes");
    options.motion_blur = args->Flag("motion-blur");
    if (args->Flag("auto-exposure") && args->Flag("no-auto-exposure"))
      throw std::invalid_argument("--auto-exposure and --no-auto-exposure exclude each other");
    if (args->Flag("auto-exposure")) options.auto_exposure = true;
    if (args->Flag("no-auto-exposure")) options.auto_exposure = false;
    if (const std::optional<std::string> size = args->Value("resolution")) {
      int width = 0, height = 0;
      char x = 0, rest = 0;
      if (std::sscanf(size->c_str(), "%d%c%d%c", &width, &x, &height, &rest) != 3 || x != 'x')
        throw std::invalid_argument("--resolution must be WIDTHxHEIGHT, e.g. 512x384");
      options.resolution = cv::Size(width, height);
    }
    options.Validate();
  } catch (const std::invalid_argument& error) {
    std::fprintf(stderr, "make_synthetic_sequence: %s\n%s", error.what(), kUsage);
    return 2;
  }
  try {
    const datasets::SyntheticSequence sequence(options);
    std::printf("rendering %s: %s, route %s, %.1f s, %d frames, seed %llu\n", out.c_str(),
                options.scene.c_str(), options.route.c_str(), options.seconds,
                sequence.frame_count(), static_cast<unsigned long long>(options.seed));
    sequence.Write(out, [](int frame, int frames) {
      if (frame % 100 == 0 || frame == frames)
        std::fprintf(stderr, "  %d / %d frames\n", frame, frames);
    });
    if (!args->Flag("no-bag")) {
      ros_conversions::WriteEurocBag(datasets::EurocSequence::Open(out), out + "/sequence.bag");
      std::printf("wrote %s/sequence.bag\n", out.c_str());
    }
  } catch (const std::exception& error) {
    std::fprintf(stderr, "make_synthetic_sequence: %s\n", error.what());
    return 1;
  }
  return 0;
}
