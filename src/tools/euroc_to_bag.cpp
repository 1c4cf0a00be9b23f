// Writes an EuRoC ASL sequence into a rosbag: /cam0/image_raw, /cam1/image_raw (mono8, stamp =
// image timestamp) and, when the sequence has ground truth, /ground_truth (body pose in world).
#include <cstdio>
#include <exception>
#include <optional>
#include <string>

#include <geometry_msgs/PoseStamped.h>
#include <rosbag/bag.h>

#include "command_line.h"
#include "ros_conversions.h"
#include "stereo_fabmap_slam/io/euroc_sequence.h"

namespace {

using namespace stereo_fabmap_slam;  // NOLINT: a tool's main file

constexpr char kUsage[] =
    "usage: euroc_to_bag ASL_DIR OUT.bag\n"
    "Writes /cam0/image_raw and /cam1/image_raw (sensor_msgs/Image, mono8, frame ids cam0 and\n"
    "cam1) and, when ASL_DIR has ground truth, /ground_truth (geometry_msgs/PoseStamped, body\n"
    "frame in 'world').\n";

void WriteGroundTruth(const evaluation::StampedPose& body, rosbag::Bag* bag) {
  geometry_msgs::PoseStamped message;
  message.header.stamp.fromSec(body.timestamp);
  message.header.frame_id = "world";
  message.pose = ros_conversions::ToPoseMessage(body.pose);
  bag->write("/ground_truth", message.header.stamp, message);
}

// Writes messages in time order, as a recorded bag has them: ground truth runs at 200 Hz and
// starts before the first image and ends after the last.
void WriteBag(const io::EurocSequence& sequence, const std::string& bag_path) {
  rosbag::Bag bag(bag_path, rosbag::bagmode::Write);
  const evaluation::Trajectory& truth = sequence.ground_truth();
  std::size_t next_truth = 0;
  for (std::size_t i = 0; i < sequence.size(); ++i) {
    const io::StereoImages images = sequence.LoadStereoPair(i);
    const ros::Time stamp = ros_conversions::ToRosTime(images.timestamp_ns);
    for (; next_truth < truth.size() && truth[next_truth].timestamp <= stamp.toSec();
         ++next_truth) {
      WriteGroundTruth(truth[next_truth], &bag);
    }
    bag.write("/cam0/image_raw", stamp,
              ros_conversions::ToMono8ImageMessage(images.left, stamp, "cam0"));
    bag.write("/cam1/image_raw", stamp,
              ros_conversions::ToMono8ImageMessage(images.right, stamp, "cam1"));
    if ((i + 1) % 500 == 0) std::fprintf(stderr, "  %zu / %zu frames\n", i + 1, sequence.size());
  }
  for (; next_truth < truth.size(); ++next_truth) WriteGroundTruth(truth[next_truth], &bag);
  bag.close();
}

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
    const io::EurocSequence sequence = io::EurocSequence::Open(args->positional()[0]);
    for (const io::UnpairedImage& image : sequence.unpaired()) {
      std::fprintf(stderr, "euroc_to_bag: warning: %s image %s has no partner, skipped\n",
                   image.camera.c_str(), image.path.c_str());
    }
    WriteBag(sequence, args->positional()[1]);
    std::printf("wrote %s: %zu stereo pairs, %zu ground-truth poses\n",
                args->positional()[1].c_str(), sequence.size(), sequence.ground_truth().size());
  } catch (const std::exception& error) {
    std::fprintf(stderr, "euroc_to_bag: %s\n", error.what());
    return 1;
  }
  return 0;
}
