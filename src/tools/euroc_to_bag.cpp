// Writes an EuRoC ASL sequence into a rosbag: /cam0/image_raw, /cam1/image_raw (mono8, stamp =
// image timestamp) and, when the sequence has ground truth, /ground_truth (body pose in world).
#include <cstdio>
#include <exception>
#include <optional>
#include <string>

#include "command_line.h"
#include "euroc_bag_writer.h"
#include "stereo_fabmap_slam/datasets/euroc_sequence.h"

namespace {

using namespace stereo_fabmap_slam;  // NOLINT: a tool's main file

constexpr char kUsage[] =
    "usage: euroc_to_bag ASL_DIR OUT.bag\n"
    "Writes /cam0/image_raw and /cam1/image_raw (sensor_msgs/Image, mono8, frame ids cam0 and\n"
    "cam1) and, when ASL_DIR has ground truth, /ground_truth (geometry_msgs/PoseStamped, body\n"
    "frame in 'world').\n";

}  // namespace

int main(int argc, char** argv) {
  std::optional<tools::CommandLine> args;
  try {
    args.emplace(argc, argv, std::set<std::string>{}, std::set<std::string>{"help"});
    if (args->Flag("help")) {
      std::fputs(kUsage, stdout);
      return 0;
    }
    if (args->positional().size() != 2) throw std::invalid_argument("expected ASL_DIR and OUT.bag");
  } catch (const std::invalid_argument& error) {
    std::fprintf(stderr, "euroc_to_bag: %s\n%s", error.what(), kUsage);
    return 2;
  }
  try {
    const datasets::EurocSequence sequence = datasets::EurocSequence::Open(args->positional()[0]);
    for (const datasets::UnpairedImage& image : sequence.unpaired()) {
      std::fprintf(stderr, "euroc_to_bag: warning: %s image %s has no partner, skipped\n",
                   image.camera.c_str(), image.path.c_str());
    }
    ros_conversions::WriteEurocBag(sequence, args->positional()[1]);
    std::printf("wrote %s: %zu stereo pairs, %zu ground-truth poses\n",
                args->positional()[1].c_str(), sequence.size(), sequence.ground_truth().size());
  } catch (const std::exception& error) {
    std::fprintf(stderr, "euroc_to_bag: %s\n", error.what());
    return 1;
  }
  return 0;
}
