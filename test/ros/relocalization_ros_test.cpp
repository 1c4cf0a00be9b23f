// The relocalize service and the recovery after tracking loss through the three nodelets, on a
// rendered kidnap route (at 60 % of its time the camera jumps back half a lap):
// - before any keyframe, relocalize answers "map is empty";
// - after the jump, the new piece of odometry is joined to the map in map_graph (by the
//   tracker's recovery, a RELOCALIZATION edge, or by a loop the loop detector closed first), and
//   a relocalize call succeeds with a pose close to ground truth;
// - after the bag ended, relocalize times out: no images;
// - save_map writes the map (once at 12 s, once at the end); load_map refuses a damaged file
//   (the map stays as it was) and loads the early map in place of the whole one; in
//   localization mode a replay of the bag's start is found in it (pose against ground truth,
//   map -> odom corrections) and adds no keyframe; back in mapping mode a replay extends the map
//   again, its new piece of odometry joined to it.
#include <sys/wait.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <csignal>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <limits>
#include <map>
#include <mutex>
#include <numeric>
#include <set>
#include <string>
#include <thread>
#include <utility>
#include <vector>

#include <geometry_msgs/TransformStamped.h>
#include <gtest/gtest.h>
#include <nav_msgs/Odometry.h>
#include <ros/ros.h>
#include <stereo_fabmap_slam/MapFile.h>
#include <stereo_fabmap_slam/MapGraph.h>
#include <stereo_fabmap_slam/Relocalize.h>
#include <stereo_fabmap_slam/SetMode.h>

#include "ros_conversions.h"
#include "stereo_fabmap_slam/datasets/euroc_sequence.h"
#include "stereo_fabmap_slam/evaluation/trajectory_metrics.h"
#include "test_support.h"

namespace stereo_fabmap_slam::test {
namespace {

constexpr double kSeconds = 40.0;
constexpr double kCut = 0.6 * kSeconds;  // the kidnap route's jump
// [m] A relocalized pose against ground truth: the map's drift at the place and the
// relocalization's error (see the first use).
constexpr double kMapDriftBound = 0.15;

Eigen::Isometry3d PoseAt(const evaluation::Trajectory& trajectory, double time) {
  double best = std::numeric_limits<double>::max();
  Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
  for (const auto& entry : trajectory) {
    if (std::abs(entry.timestamp - time) < best) {
      best = std::abs(entry.timestamp - time);
      pose = entry.pose;
    }
  }
  EXPECT_LT(best, 0.01) << "no ground truth near " << time;
  return pose;
}

// The pieces of odometry in a map_graph (a piece ends where two consecutive keyframes have no
// odometry edge: a tracking loss, a reset, a loaded map) and what joins them. A piece that
// starts after a break is joined to the map either by the recovery's relocalization edge or by
// a loop that the loop detector closed first: the two run side by side in the graph, and which
// one is first depends on the machine's load, so a test of the recovery accepts both.
struct GraphPieces {
  int breaks = 0;
  bool newest_in_map = false;       // the newest keyframe is joined to the map's first
  int joining_relocalizations = 0;  // edges between different pieces, by type
  int joining_loops = 0;
};

GraphPieces DescribePieces(const stereo_fabmap_slam::MapGraph& graph) {
  GraphPieces pieces;
  if (graph.keyframe_ids.empty()) return pieces;
  std::set<std::pair<std::uint64_t, std::uint64_t>> odometry;
  for (const auto& edge : graph.edges) {
    if (edge.type == stereo_fabmap_slam::MapGraphEdge::ODOMETRY) {
      odometry.emplace(std::min(edge.from_id, edge.to_id), std::max(edge.from_id, edge.to_id));
    }
  }
  std::vector<std::size_t> order(graph.keyframe_ids.size());
  std::iota(order.begin(), order.end(), 0);
  std::sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) {
    return graph.keyframe_ids[a] < graph.keyframe_ids[b];
  });
  std::map<std::uint64_t, int> piece_of;
  for (std::size_t k = 0; k < order.size(); ++k) {
    const std::uint64_t id = graph.keyframe_ids[order[k]];
    if (k > 0 && odometry.count({graph.keyframe_ids[order[k - 1]], id}) == 0) ++pieces.breaks;
    piece_of[id] = pieces.breaks;
  }
  pieces.newest_in_map = graph.keyframe_in_map.size() == graph.keyframe_ids.size() &&
                         graph.keyframe_in_map[order.back()];
  for (const auto& edge : graph.edges) {
    if (!piece_of.count(edge.from_id) || !piece_of.count(edge.to_id) ||
        piece_of[edge.from_id] == piece_of[edge.to_id]) {
      continue;
    }
    pieces.joining_relocalizations +=
        edge.type == stereo_fabmap_slam::MapGraphEdge::RELOCALIZATION ? 1 : 0;
    pieces.joining_loops += edge.type == stereo_fabmap_slam::MapGraphEdge::LOOP ? 1 : 0;
  }
  return pieces;
}

TEST(RelocalizationRos, KidnapRouteThroughTheNodelets) {
  TemporaryDirectory temp;
  // The sequence loop_closing_test relocalizes in offline.
  const std::string sequence =
      SharedSyntheticSequence(MAKE_SYNTHETIC_SEQUENCE_BIN, "kidnap", static_cast<int>(kSeconds), 2);
  ASSERT_FALSE(sequence.empty());
  // Ground truth of the body (base_link; the map frame is its pose at the first frame).
  const datasets::EurocSequence asl = datasets::EurocSequence::Open(sequence);
  const evaluation::Trajectory& truth = asl.ground_truth();

  std::mutex mutex;
  double first_stamp = -1, last_stamp = -1;
  int corrections = 0;              // map -> odom corrections seen
  GraphPieces latest_pieces;        // of the latest map_graph
  std::size_t graph_keyframes = 0;  // in the latest map_graph
  ros::NodeHandle node;
  const ros::Subscriber odometry_subscriber = node.subscribe<nav_msgs::Odometry>(
      "/odometry", 100, [&](const nav_msgs::OdometryConstPtr& message) {
        std::lock_guard<std::mutex> lock(mutex);
        if (first_stamp < 0) first_stamp = message->header.stamp.toSec();
        last_stamp = message->header.stamp.toSec();
      });
  const ros::Subscriber graph_subscriber = node.subscribe<stereo_fabmap_slam::MapGraph>(
      "/map_graph", 10, [&](const stereo_fabmap_slam::MapGraphConstPtr& message) {
        std::lock_guard<std::mutex> lock(mutex);
        latest_pieces = DescribePieces(*message);
        graph_keyframes = message->keyframe_ids.size();
      });
  const ros::Subscriber correction_subscriber = node.subscribe<geometry_msgs::TransformStamped>(
      "/map_to_odom_correction", 100, [&](const geometry_msgs::TransformStampedConstPtr&) {
        std::lock_guard<std::mutex> lock(mutex);
        ++corrections;
      });
  ros::AsyncSpinner spinner(2);
  spinner.start();

  // The graph keeps running after the bag (exit_at_end:=false); playback starts after 8 s, so
  // the first call finds no map.
  const std::string pid_file = temp.path() + "/roslaunch.pid";
  ASSERT_EQ(std::system(("roslaunch --wait stereo_fabmap_slam euroc_bag.launch bag:=" + sequence +
                         "/sequence.bag calibration:=" + sequence +
                         "/stereo_calibration.yaml delay:=8 exit_at_end:=false > " + temp.path() +
                         "/roslaunch.log 2>&1 & echo $! > " + pid_file)
                            .c_str()),
            0);
  const int launch_pid = std::stoi(ReadTextFile(pid_file));
  ros::ServiceClient client = node.serviceClient<stereo_fabmap_slam::Relocalize>("/relocalize");
  ASSERT_TRUE(client.waitForExistence(ros::Duration(60.0)));

  stereo_fabmap_slam::Relocalize empty;
  empty.request.timeout = 1.0;
  ASSERT_TRUE(client.call(empty));
  EXPECT_FALSE(empty.response.success);
  EXPECT_EQ(empty.response.message, "map is empty");

  // Past the jump: wait (wall time) until the bag's clock is 3 s beyond it.
  const auto bag_time = [&] {
    std::lock_guard<std::mutex> lock(mutex);
    return first_stamp < 0 ? -1.0 : last_stamp - first_stamp;
  };
  const ros::WallTime deadline = ros::WallTime::now() + ros::WallDuration(kSeconds * 3 + 60);
  // A map of the first 12 s is saved on the way, to be loaded in place of the whole one later.
  ros::ServiceClient save = node.serviceClient<stereo_fabmap_slam::MapFile>("/save_map");
  stereo_fabmap_slam::MapFile early;
  early.request.path = temp.path() + "/early.map";
  bool early_saved = false;
  while (bag_time() < kCut + 3.0 && ros::WallTime::now() < deadline) {
    if (!early_saved && bag_time() > 12.0) early_saved = save.call(early);
    ros::WallDuration(0.1).sleep();
  }
  ASSERT_TRUE(early_saved);
  EXPECT_TRUE(early.response.success) << early.response.message;
  ASSERT_GE(bag_time(), kCut + 3.0) << ReadTextFile(temp.path() + "/roslaunch.log");
  // The kidnap recovery on its own (before any replay adds edges): the piece of odometry after
  // the jump is joined to the map, by the recovery's relocalization edge or by a loop closed
  // first (within a few seconds of wall time: the map_graph after it).
  const auto pieces = [&] {
    std::lock_guard<std::mutex> lock(mutex);
    return latest_pieces;
  };
  const auto joined_after_break = [](const GraphPieces& graph) {
    return graph.breaks >= 1 && graph.newest_in_map &&
           graph.joining_relocalizations + graph.joining_loops >= 1;
  };
  for (int i = 0; i < 50 && !joined_after_break(pieces()); ++i) {
    ros::WallDuration(0.1).sleep();
  }
  {
    const GraphPieces after_jump = pieces();
    EXPECT_TRUE(joined_after_break(after_jump))
        << after_jump.breaks << " breaks, newest keyframe in the map " << after_jump.newest_in_map
        << "\n"
        << ReadTextFile(temp.path() + "/roslaunch.log");
    RecordProperty("jump_joined_by_relocalization_edges", after_jump.joining_relocalizations);
    RecordProperty("jump_joined_by_loops", after_jump.joining_loops);
  }
  // A relocalized pose (of base_link) against ground truth: the map frame is the body at the
  // first frame.
  const auto pose_error = [&](const geometry_msgs::PoseStamped& pose) {
    const Eigen::Isometry3d expected =
        PoseAt(truth, truth.front().timestamp).inverse() * PoseAt(truth, pose.header.stamp.toSec());
    return expected.inverse() * ros_conversions::FromPoseMessage(pose.pose);
  };
  stereo_fabmap_slam::Relocalize after_jump;
  after_jump.request.timeout = 2.0;
  ASSERT_TRUE(client.call(after_jump));
  EXPECT_TRUE(after_jump.response.success) << after_jump.response.message;
  if (after_jump.response.success) {
    EXPECT_EQ(after_jump.response.pose.header.frame_id, "map");
    EXPECT_GE(after_jump.response.inliers, 50);
    const Eigen::Isometry3d error = pose_error(after_jump.response.pose);
    RecordProperty("pose_error_m", std::to_string(error.translation().norm()));
    RecordProperty("time_ms", std::to_string(after_jump.response.time_ms));
    // Against ground truth, so the error holds the map's own drift at the place (odometry ~1 %
    // of the 20 m before the jump, partly undone by loop closing) beside the relocalization's few
    // millimetres, and that drift depends on the pairs the graph skipped: 6.9 cm in a run alone
    // on a machine half as fast as the one the test was written on, 10.7 cm (and 8.3 cm in
    // localization below) in a fresh-clone make test there beside the sanitizer build.
    // kMapDriftBound and 3 degrees: above that, and still far from the kidnap route's look-alike
    // places, metres apart.
    EXPECT_LT(error.translation().norm(), kMapDriftBound);
    EXPECT_LT(Eigen::AngleAxisd(error.linear()).angle() * 180 / M_PI, 3.0);
  }

  // After the bag: no more images.
  while (bag_time() < kSeconds - 0.5 && ros::WallTime::now() < deadline) {
    ros::WallDuration(0.2).sleep();
  }
  ros::WallDuration(2.0).sleep();
  stereo_fabmap_slam::Relocalize no_images;
  no_images.request.timeout = 0.5;
  ASSERT_TRUE(client.call(no_images));
  EXPECT_FALSE(no_images.response.success);
  EXPECT_NE(no_images.response.message.find("no stereo images"), std::string::npos)
      << no_images.response.message;

  // Save the whole map; refuse a damaged copy (the map stays whole); load the early map in its
  // place; use it in localization mode, then map again.
  ros::ServiceClient load = node.serviceClient<stereo_fabmap_slam::MapFile>("/load_map");
  ros::ServiceClient set_mode = node.serviceClient<stereo_fabmap_slam::SetMode>("/set_mode");
  stereo_fabmap_slam::MapFile whole;
  whole.request.path = temp.path() + "/whole.map";
  ASSERT_TRUE(save.call(whole));
  EXPECT_TRUE(whole.response.success) << whole.response.message;
  EXPECT_GT(whole.response.keyframes, early.response.keyframes + 50);
  const std::string bytes = ReadTextFile(whole.request.path);
  {
    std::FILE* file = std::fopen((temp.path() + "/truncated.map").c_str(), "wb");
    ASSERT_NE(file, nullptr);
    std::fwrite(bytes.data(), 1, bytes.size() / 2, file);
    std::fclose(file);
  }
  stereo_fabmap_slam::MapFile damaged;
  damaged.request.path = temp.path() + "/truncated.map";
  ASSERT_TRUE(load.call(damaged));
  EXPECT_FALSE(damaged.response.success);
  stereo_fabmap_slam::MapFile unchanged;
  unchanged.request.path = temp.path() + "/unchanged.map";
  ASSERT_TRUE(save.call(unchanged));
  EXPECT_EQ(unchanged.response.keyframes, whole.response.keyframes)
      << "the refused load changed the map";

  stereo_fabmap_slam::MapFile loaded;
  loaded.request.path = early.request.path;
  ASSERT_TRUE(load.call(loaded));
  EXPECT_TRUE(loaded.response.success) << loaded.response.message;
  EXPECT_EQ(loaded.response.keyframes, early.response.keyframes);
  // The Backend rebuilds its graph from the file: map_graph shrinks to the early map.
  const auto graph_size = [&] {
    std::lock_guard<std::mutex> lock(mutex);
    return graph_keyframes;
  };
  for (int i = 0; i < 100 && graph_size() != early.response.keyframes; ++i) {
    ros::WallDuration(0.1).sleep();
  }
  EXPECT_EQ(graph_size(), early.response.keyframes);
  stereo_fabmap_slam::SetMode localization;
  localization.request.mode = "localization";
  ASSERT_TRUE(set_mode.call(localization));
  EXPECT_TRUE(localization.response.success) << localization.response.message;
  stereo_fabmap_slam::SetMode unknown_mode;
  unknown_mode.request.mode = "exploring";
  ASSERT_TRUE(set_mode.call(unknown_mode));
  EXPECT_FALSE(unknown_mode.response.success);

  // A replay of the bag's first 10 s (time goes back: the tracker starts afresh), with a
  // relocalize call in its middle.
  const auto replay = [&](double seconds, stereo_fabmap_slam::Relocalize* call) {
    bool called = false;
    std::thread caller([&] {
      ros::WallDuration(seconds / 2).sleep();
      call->request.timeout = 2.0;
      called = client.call(*call);
    });
    EXPECT_EQ(std::system(("rosbag play --clock --quiet -u " + std::to_string(seconds) + " " +
                           sequence + "/sequence.bag > " + temp.path() + "/replay.log 2>&1")
                              .c_str()),
              0);
    caller.join();
    ros::WallDuration(1.0).sleep();
    return called;
  };
  stereo_fabmap_slam::Relocalize replayed;
  ASSERT_TRUE(replay(10.0, &replayed));
  EXPECT_TRUE(replayed.response.success) << replayed.response.message;
  if (replayed.response.success) {
    const Eigen::Isometry3d error = pose_error(replayed.response.pose);
    RecordProperty("localization_pose_error_m", std::to_string(error.translation().norm()));
    EXPECT_LT(error.translation().norm(), kMapDriftBound);
  }
  {
    std::lock_guard<std::mutex> lock(mutex);
    EXPECT_GT(corrections, 0);                             // map -> odom from relocalizations
    EXPECT_EQ(graph_keyframes, early.response.keyframes);  // localization adds no keyframe
    EXPECT_EQ(latest_pieces.breaks, 0);                    // the early map is one piece
  }

  // Mapping again: the odometry goes on in a new piece, which recovery joins to the map.
  stereo_fabmap_slam::SetMode mapping;
  mapping.request.mode = "mapping";
  ASSERT_TRUE(set_mode.call(mapping));
  EXPECT_TRUE(mapping.response.success);
  stereo_fabmap_slam::Relocalize remapped;
  ASSERT_TRUE(replay(6.0, &remapped));
  // The replay's start lies in the early map: found, as in localization mode.
  EXPECT_TRUE(remapped.response.success) << remapped.response.message;
  if (remapped.response.success) {
    const Eigen::Isometry3d error = pose_error(remapped.response.pose);
    RecordProperty("remapped_pose_error_m", std::to_string(error.translation().norm()));
    EXPECT_LT(error.translation().norm(), kMapDriftBound);
  }
  {
    std::lock_guard<std::mutex> lock(mutex);
    EXPECT_GT(graph_keyframes, early.response.keyframes);  // the map grows again
    EXPECT_TRUE(joined_after_break(latest_pieces));        // the new piece joined to it
    RecordProperty("replay_joined_by_relocalization_edges", latest_pieces.joining_relocalizations);
  }

  kill(launch_pid, SIGINT);
  for (int i = 0; i < 150 && kill(launch_pid, 0) == 0; ++i) ros::WallDuration(0.1).sleep();
  spinner.stop();
}

}  // namespace
}  // namespace stereo_fabmap_slam::test

int main(int argc, char** argv) {
  testing::InitGoogleTest(&argc, argv);
  ros::init(argc, argv, "relocalization_ros_test");
  return RUN_ALL_TESTS();
}
