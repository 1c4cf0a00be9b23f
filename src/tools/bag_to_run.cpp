// Turns a bag recorded from the nodelet graph into the files run_dataset writes, as the
// Recorder nodelet (output:=DIR) would have written them live.
#include <cstdio>
#include <filesystem>
#include <optional>
#include <set>
#include <string>
#include <vector>

#include <rosbag/bag.h>
#include <rosbag/view.h>

#include "command_line.h"
#include "run_recorder.h"

namespace {

using namespace stereo_fabmap_slam;  // NOLINT: a tool's main file

constexpr char kUsage[] =
    "usage: bag_to_run RECORDED.bag --output DIR [--no-loop-closing]\n"
    "Writes the run a bag recorded from the graph holds (its /tracked_frames, /keyframes,\n"
    "/keyframe_updates, /place_results, /map_graph, /map_loaded and /mode) as run_dataset writes\n"
    "its runs: DIR/trajectory.txt (map frame, every frame; in localization mode through the\n"
    "map -> odom in force at each frame), odometry.txt, keyframes.txt, loops.csv, timing.csv,\n"
    "summary.json. The same as euroc_bag.launch output:=DIR writes live. Record with\n"
    "  rosbag record /tracked_frames /keyframes /keyframe_updates /place_results /map_graph \\\n"
    "    /map_loaded /mode\n";

}  // namespace

int main(int argc, char** argv) {
  std::optional<tools::CommandLine> args;
  try {
    args.emplace(argc, argv, std::set<std::string>{"output"},
                 std::set<std::string>{"help", "no-loop-closing"});
    if (args->Flag("help")) {
      std::fputs(kUsage, stdout);
      return 0;
    }
    if (args->positional().size() != 1) throw std::invalid_argument("expected one RECORDED.bag");
    if (!args->Value("output")) throw std::invalid_argument("--output DIR is required");
  } catch (const std::invalid_argument& error) {
    std::fprintf(stderr, "bag_to_run: %s\n%s", error.what(), kUsage);
    return 2;
  }
  try {
    rosbag::Bag bag(args->positional()[0], rosbag::bagmode::Read);
    ros_wiring::RunRecorder recorder(!args->Flag("no-loop-closing"));
    rosbag::View view(bag);
    std::size_t messages = 0;
    for (const rosbag::MessageInstance& m : view) {
      const std::string& topic = m.getTopic();
      ++messages;
      if (topic == "/tracked_frames") {
        if (auto frame = m.instantiate<stereo_fabmap_slam::TrackedFrame>()) {
          recorder.OnTrackedFrame(*frame, 0);
        }
      } else if (topic == "/keyframes") {
        if (auto keyframe = m.instantiate<stereo_fabmap_slam::Keyframe>()) {
          recorder.OnKeyframe(*keyframe);
        }
      } else if (topic == "/keyframe_updates") {
        if (auto update = m.instantiate<stereo_fabmap_slam::KeyframeUpdate>()) {
          recorder.OnUpdate(*update);
        }
      } else if (topic == "/place_results") {
        if (auto result = m.instantiate<stereo_fabmap_slam::PlaceResult>()) {
          recorder.OnPlaceResult(*result);
        }
      } else if (topic == "/map_graph") {
        if (auto graph = m.instantiate<stereo_fabmap_slam::MapGraph>()) recorder.OnMapGraph(*graph);
      } else if (topic == "/map_loaded") {
        if (auto loaded = m.instantiate<stereo_fabmap_slam::MapLoaded>()) {
          const std::string problem = recorder.OnMapLoaded(*loaded);
          if (!problem.empty()) std::fprintf(stderr, "bag_to_run: warning: %s\n", problem.c_str());
        }
      } else if (topic == "/mode") {
        if (auto mode = m.instantiate<std_msgs::String>()) recorder.OnMode(*mode);
      } else {
        --messages;
      }
    }
    if (recorder.frames() == 0) {
      throw std::runtime_error("no /tracked_frames in " + args->positional()[0] +
                               ": record the graph's topics (see --help)");
    }
    const std::string output = *args->Value("output");
    recorder.Write(output, std::filesystem::path(output).filename().string());
    std::printf("wrote %s: %zu frames from %zu messages\n", output.c_str(), recorder.frames(),
                messages);
  } catch (const std::exception& error) {
    std::fprintf(stderr, "bag_to_run: %s\n", error.what());
    return 1;
  }
  return 0;
}
