// One SLAM, two drivers: the nodelet graph played in lockstep (euroc_bag.launch lockstep:=true,
// output:=DIR, save_map:=FILE) computes what run_dataset computes on the same sequence, on
// MH01_first10s and on a rendered loop with loop closing: the same keyframes, the same accepted
// loops, the trajectories within 0.5 mm RMS with no alignment (they agree to the last printed
// digit: both drivers run the same stages in the same order), and the same saved map, which
// each driver then loads for localization (MH01). The graph's odom is REP-105's, the base at the
// first frame; the test mounts the base at the rectified left camera so that odom and map are
// run_dataset's frames (~base_to_camera), as a user comparing the two would.
#include <sys/wait.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <map>
#include <set>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

#include <gtest/gtest.h>
#include <ros/ros.h>

#include "euroc_bag_fixture.h"
#include "saved_maps.h"
#include "stereo_fabmap_slam/camera/camera_calibration.h"
#include "stereo_fabmap_slam/camera/camera_options.h"
#include "stereo_fabmap_slam/camera/stereo_rectifier.h"
#include "stereo_fabmap_slam/datasets/euroc_sequence.h"
#include "stereo_fabmap_slam/io/options_file.h"
#include "stereo_fabmap_slam/io/trajectory_file.h"
#include "stereo_fabmap_slam/map/map_file.h"
#include "test_support.h"

namespace stereo_fabmap_slam::test {
namespace {

// A sequence as both drivers take it: its ASL folder, a bag of it, and its calibration.
struct Sequence {
  std::string asl, bag, calibration, base_to_camera;
};

// The raw left camera in the rectified left camera's frame, as ~base_to_camera's list: with it
// the base is the rectified left camera, and the graph's odom is run_dataset's first camera.
std::string BaseAtRectifiedLeftCamera(const camera::StereoCalibration& calibration) {
  const camera::RectificationOptions options =
      io::OptionsFile::Load(RepositoryRoot() + "/config/euroc.yaml")
          .Read(camera::RectificationOptions());
  const camera::StereoRectifier rectifier =
      camera::StereoRectifier::FromCalibration(calibration, options);
  const Eigen::Isometry3d T =
      rectifier.T_body_rectified_left().inverse() * calibration.left.T_body_camera;
  const Eigen::Quaterniond q(T.linear());
  char text[256];
  // All 17 digits: the frames must agree to the last bit for the runs to (a rounded mounting
  // moves the first pose by 1e-14 rad, which can tip one RANSAC inlier the other way).
  std::snprintf(text, sizeof(text), "[%.17g, %.17g, %.17g, %.17g, %.17g, %.17g, %.17g]",
                T.translation().x(), T.translation().y(), T.translation().z(), q.x(), q.y(), q.z(),
                q.w());
  return text;
}

Sequence Prepare(const std::string& asl, const std::string& bag, const std::string& folder) {
  Sequence sequence{asl, bag, folder + "/stereo_calibration.yaml", ""};
  const camera::StereoCalibration calibration = datasets::EurocSequence::Open(asl).calibration();
  camera::WriteStereoCalibrationYaml(calibration, sequence.calibration);
  sequence.base_to_camera = BaseAtRectifiedLeftCamera(calibration);
  return sequence;
}

void RunDataset(const std::string& asl, const std::string& output, const std::string& extra) {
  std::string log;
  ASSERT_EQ(RunCommand(std::string(RUN_DATASET_BIN) + " " + asl + " --quiet --output " + output +
                           " " + extra + " 2>&1",
                       &log),
            0)
      << log;
}

// The topics a recorded run needs (bag_to_run's input).
const std::vector<std::string> kRunTopics = {
    "/tracked_frames", "/keyframe_updates", "/keyframes", "/place_results",
    "/map_graph",      "/map_loaded",       "/mode"};

// Whether the master lists a subscriber of every topic of kRunTopics. rosbag's recorder registers
// its subscriptions as it starts; it connects to each publisher when the master announces it,
// which the lockstep player's start (all the graph's topics advertised, then a second) leaves
// time for.
bool RecorderSubscribed() {
  XmlRpc::XmlRpcValue request, response, payload;
  request[0] = ros::this_node::getName();
  if (!ros::master::execute("getSystemState", request, response, payload, false)) return false;
  std::set<std::string> subscribed;
  XmlRpc::XmlRpcValue& subscribers = payload[1];
  for (int i = 0; i < subscribers.size(); ++i) {
    subscribed.insert(static_cast<std::string>(subscribers[i][0]));
  }
  for (const std::string& topic : kRunTopics) {
    if (subscribed.count(topic) == 0) return false;
  }
  return true;
}

// The graph on the sequence in lockstep, until the bag ends; `extra`: more launch arguments.
// With `recorded`, its topics are recorded into that bag too.
void RunGraph(const Sequence& sequence, const std::string& output, const std::string& extra,
              const std::string& recorded = "") {
  const std::string log_path = output + ".roslaunch.log";
  const std::string recorder_pid = output + ".record.pid";
  if (!recorded.empty()) {
    std::string topics;
    for (const std::string& topic : kRunTopics) topics += " " + topic;
    // rosbag's recorder itself (not the `rosbag record` script), so that SIGINT closes the bag.
    ASSERT_EQ(std::system(("/usr/lib/rosbag/record -q -O " + recorded + topics +
                           " > /dev/null 2>&1 & echo $! > " + recorder_pid)
                              .c_str()),
              0);
    const ros::WallTime give_up = ros::WallTime::now() + ros::WallDuration(60.0);
    while (!RecorderSubscribed() && ros::WallTime::now() < give_up) {
      ros::WallDuration(0.1).sleep();
    }
    ASSERT_TRUE(RecorderSubscribed()) << "rosbag record did not subscribe within 60 s";
  }
  const int status = std::system(
      ("roslaunch --wait stereo_fabmap_slam euroc_bag.launch lockstep:=true exit_at_end:=true "
       "visualizer:=false bag:=" +
       sequence.bag + " calibration:=" + sequence.calibration + " base_to_camera:='" +
       sequence.base_to_camera + "' output:=" + output + " " + extra + " > " + log_path + " 2>&1")
          .c_str());
  if (!recorded.empty()) {
    // The graph's last messages may still be in the recorder's socket when roslaunch returns.
    ros::WallDuration(1.0).sleep();
    const long pid = std::stol(ReadTextFile(recorder_pid));
    // Interrupted, it writes the bag out and renames it from .active; wait for that.
    ASSERT_EQ(std::system(("kill -INT " + std::to_string(pid) + " && while kill -0 " +
                           std::to_string(pid) + " 2> /dev/null; do sleep 0.1; done")
                              .c_str()),
              0);
  }
  const std::string log = ReadTextFile(log_path);
  ASSERT_TRUE(WIFEXITED(status) && WEXITSTATUS(status) == 0) << log;
  EXPECT_NE(log.find("lockstep_player: played"), std::string::npos) << log;
  EXPECT_NE(log.find(", 0 without an answer"), std::string::npos) << log;
}

std::set<std::pair<long, long>> AcceptedLoops(const std::string& folder) {
  std::set<std::pair<long, long>> loops;
  std::istringstream lines(ReadTextFile(folder + "/loops.csv"));
  std::string line;
  std::getline(lines, line);  // header
  while (std::getline(lines, line)) {
    long query = 0, match = 0;
    int inliers = 0, accepted = 0;
    double query_time = 0, match_time = 0, probability = 0;
    if (std::sscanf(line.c_str(), "%ld,%lf,%ld,%lf,%lf,%d,%d", &query, &query_time, &match,
                    &match_time, &probability, &inliers, &accepted) == 7 &&
        accepted == 1) {
      loops.insert({query, match});
    }
  }
  return loops;
}

// RMS [m] of the position differences of two trajectories' poses at the same stamps, with no
// alignment; every pose of `a` must have its stamp in `b` and the other way round.
double RmsDifference(const std::string& a_path, const std::string& b_path) {
  const io::Trajectory a = io::ReadTumTrajectory(a_path);
  const io::Trajectory b = io::ReadTumTrajectory(b_path);
  EXPECT_EQ(a.size(), b.size()) << a_path << " / " << b_path;
  std::map<long long, Eigen::Vector3d> positions;
  for (const io::StampedPose& pose : b) {
    positions[std::llround(pose.timestamp * 1e6)] = pose.pose.translation();
  }
  double sum = 0;
  for (const io::StampedPose& pose : a) {
    const auto it = positions.find(std::llround(pose.timestamp * 1e6));
    if (it == positions.end()) {
      ADD_FAILURE() << "no pose at " << pose.timestamp << " in " << b_path;
      continue;
    }
    sum += (pose.pose.translation() - it->second).squaredNorm();
  }
  return a.empty() ? 0.0 : std::sqrt(sum / a.size());
}

// Both drivers on one sequence; with `cross_load`, each then localizes in the other's map.
void CheckBothDrivers(const Sequence& sequence, const std::string& folder, bool expect_loops,
                      bool cross_load) {
  const std::string offline = folder + "/offline", graph = folder + "/graph";
  RunDataset(sequence.asl, offline, "--save-map " + folder + "/offline.map");
  RunGraph(sequence, graph, "save_map:=" + folder + "/graph.map",
           cross_load ? folder + "/recorded.bag" : "");
  const std::string offline_summary = ReadTextFile(offline + "/summary.json");
  const std::string graph_summary = ReadTextFile(graph + "/summary.json");
  for (const char* key : {"frames", "keyframes", "map_keyframes", "trajectory_frames",
                          "relocalizations", "frames_lost"}) {
    EXPECT_EQ(JsonNumber(graph_summary, key), JsonNumber(offline_summary, key)) << key;
  }
  EXPECT_EQ(JsonNumber(graph_summary, "pairs_skipped"), 0) << "lockstep skips nothing";
  const auto loops = AcceptedLoops(offline);
  EXPECT_EQ(AcceptedLoops(graph), loops);
  if (expect_loops) {
    EXPECT_GT(loops.size(), 10u);
  }
  // Trajectories: 0.5 mm RMS with no alignment is the bound the two drivers must meet; they
  // run the same stages in the same order, and meet it to the last printed digit.
  const double trajectory = RmsDifference(offline + "/trajectory.txt", graph + "/trajectory.txt");
  const double odometry = RmsDifference(offline + "/odometry.txt", graph + "/odometry.txt");
  const double keyframes = RmsDifference(offline + "/keyframes.txt", graph + "/keyframes.txt");
  ::testing::Test::RecordProperty("trajectory_rms_mm", std::to_string(trajectory * 1000));
  ::testing::Test::RecordProperty("odometry_rms_mm", std::to_string(odometry * 1000));
  EXPECT_LT(trajectory, 0.0005);
  EXPECT_LT(odometry, 0.0005);
  EXPECT_LT(keyframes, 0.0005);

  const map::SavedMap offline_map = map::LoadMapFile(folder + "/offline.map");
  const map::SavedMap graph_map = map::LoadMapFile(folder + "/graph.map");
  ExpectSameMaps(offline_map, graph_map, 1e-9, 1e-9);
  if (!cross_load) return;

  // The graph's topics recorded, turned into the same files afterwards.
  std::string log;
  ASSERT_EQ(RunCommand(std::string(BAG_TO_RUN_BIN) + " " + folder + "/recorded.bag --output " +
                           folder + "/from_bag 2>&1",
                       &log),
            0)
      << log;
  for (const char* file : {"trajectory.txt", "odometry.txt", "keyframes.txt", "loops.csv"}) {
    EXPECT_EQ(ReadTextFile(folder + "/from_bag/" + file), ReadTextFile(graph + "/" + file)) << file;
  }

  // Each driver localizes in the other's map: every keyframe relocalized, the frames in the map.
  RunDataset(sequence.asl, folder + "/offline_in_graph_map",
             "--load-map " + folder + "/graph.map --mode localization");
  const std::string localized = ReadTextFile(folder + "/offline_in_graph_map/summary.json");
  EXPECT_GT(JsonNumber(localized, "relocalizations"), 0);
  EXPECT_GE(JsonNumber(localized, "trajectory_frames"), 0.9 * JsonNumber(localized, "frames"));
  RunGraph(sequence, folder + "/graph_in_offline_map",
           "map_file:=" + folder + "/offline.map mode:=localization", folder + "/localized.bag");
  const std::string graph_localized = ReadTextFile(folder + "/graph_in_offline_map/summary.json");
  EXPECT_GT(JsonNumber(graph_localized, "relocalizations"), 0);
  // A recording in localization mode becomes the same files too (trajectory.txt: map -> odom
  // composed per frame with the correction in force at that frame).
  ASSERT_EQ(RunCommand(std::string(BAG_TO_RUN_BIN) + " " + folder + "/localized.bag --output " +
                           folder + "/localized_from_bag 2>&1",
                       &log),
            0)
      << log;
  for (const char* file : {"trajectory.txt", "odometry.txt", "keyframes.txt"}) {
    EXPECT_EQ(ReadTextFile(folder + "/localized_from_bag/" + file),
              ReadTextFile(folder + "/graph_in_offline_map/" + file))
        << file;
  }
  // The same localization from both drivers: map -> odom per frame from the same
  // relocalizations (trajectory.txt holds T_map_camera of each frame in localization mode).
  EXPECT_LT(RmsDifference(folder + "/offline_in_graph_map/trajectory.txt",
                          folder + "/graph_in_offline_map/trajectory.txt"),
            0.0005);
}

TEST(Lockstep, Mh01GraphEqualsRunDataset) {
  TemporaryDirectory temp;
  const std::string bag = temp.path() + "/mh01.bag";
  WriteEurocSubsetBag("MH01_first10s", bag);
  CheckBothDrivers(Prepare(EurocSequencePath("MH01_first10s"), bag, temp.path()), temp.path(),
                   /*expect_loops=*/false, /*cross_load=*/true);
}

TEST(Lockstep, RenderedLoopWithLoopClosingGraphEqualsRunDataset) {
  TemporaryDirectory temp;
  // The route loop_closing_test and loop_closing_ros_test use: back past its start at 26 s.
  const std::string sequence = SharedSyntheticSequence(MAKE_SYNTHETIC_SEQUENCE_BIN, "loop", 34, 1);
  ASSERT_FALSE(sequence.empty());
  // Loading each other's maps is MH01's to show; here the loops and the pose graph.
  CheckBothDrivers(Prepare(sequence, sequence + "/sequence.bag", temp.path()), temp.path(),
                   /*expect_loops=*/true, /*cross_load=*/false);
}

}  // namespace
}  // namespace stereo_fabmap_slam::test

int main(int argc, char** argv) {
  testing::InitGoogleTest(&argc, argv);
  ros::init(argc, argv, "lockstep_test");
  return RUN_ALL_TESTS();
}
