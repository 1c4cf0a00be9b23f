// Times PoseGraph::Optimize() on a synthetic trajectory: laps of a 40 m circle with odometry that
// drifts (biased and noisy heading, noisy translation) and loop edges measured from the truth at
// revisits. Two cases:
//  - batch: all keyframes and loops, then one Optimize() from the raw odometry (the worst case:
//    every loop closes at once), repeated on fresh graphs;
//  - incremental: what the backend does, Optimize() after each loop as it arrives, warm started.
// Usage: benchmark_pose_graph [--keyframes N] [--loops M] [--repetitions R]
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <random>
#include <stdexcept>
#include <string>
#include <vector>

#include <Eigen/Geometry>

#include "command_line.h"
#include "stereo_fabmap_slam/backend/pose_graph.h"
#include "stereo_fabmap_slam/map/loop_edge.h"

namespace {

using stereo_fabmap_slam::backend::PoseGraph;
using stereo_fabmap_slam::backend::PoseGraphOptions;
using stereo_fabmap_slam::backend::PoseGraphSummary;
using stereo_fabmap_slam::map::LoopEdge;

constexpr double kPi = 3.14159265358979323846;
constexpr double kDegree = kPi / 180.0;
constexpr int kKeyframesPerLap = 100;  // 0.4 m apart on a 40 m circle

struct Scenario {
  std::vector<Eigen::Isometry3d> truth;     // T_world_camera
  std::vector<Eigen::Isometry3d> odometry;  // T_odom_camera, drifting
  std::vector<LoopEdge> loops;              // by increasing query id
};

Eigen::Isometry3d Pose(const Eigen::Vector3d& position, double yaw) {
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear() = Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  T.translation() = position;
  return T;
}

Eigen::Isometry3d SmallMotion(const Eigen::Vector3d& translation, const Eigen::Vector3d& angles) {
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  if (angles.norm() > 0)
    T.linear() = Eigen::AngleAxisd(angles.norm(), angles.normalized()).matrix();
  T.translation() = translation;
  return T;
}

Scenario MakeScenario(int keyframes, int loops, std::mt19937& random) {
  Scenario scenario;
  const double radius = 40.0 / (2 * kPi);
  for (int i = 0; i < keyframes; ++i) {
    const double angle = 2 * kPi * i / kKeyframesPerLap;
    const int lap = i / kKeyframesPerLap;
    // Laps differ by a few decimetres, so revisits have non-trivial relative poses.
    const double r = radius + 0.3 * std::sin(1.7 * lap) + 0.1 * std::sin(5 * angle);
    const Eigen::Vector3d position(r * std::cos(angle), r * std::sin(angle),
                                   0.2 * std::sin(3 * angle + lap));
    scenario.truth.push_back(Pose(position, angle + kPi / 2));
  }
  // Odometry: the true step times an error with a heading bias (the usual dominant drift of
  // stereo odometry) and white noise; the first pose is the truth, as the map starts there.
  std::normal_distribution<double> normal;
  scenario.odometry.push_back(scenario.truth[0]);
  for (int i = 1; i < keyframes; ++i) {
    const Eigen::Isometry3d step = scenario.truth[i - 1].inverse() * scenario.truth[i];
    const Eigen::Vector3d angles(0.01 * kDegree * normal(random), 0.01 * kDegree * normal(random),
                                 (0.02 + 0.02 * normal(random)) * kDegree);
    const Eigen::Vector3d translation(0.005 * normal(random), 0.005 * normal(random),
                                      0.005 * normal(random));
    scenario.odometry.push_back(scenario.odometry.back() * step * SmallMotion(translation, angles));
  }
  // Loops: a query on a later lap, matched to a keyframe within two steps of the same place.
  const double loop_translation_sigma = 0.02, loop_rotation_sigma = 0.2 * kDegree;
  Eigen::Matrix<double, 6, 1> information;
  information << Eigen::Vector3d::Constant(1 / (loop_translation_sigma * loop_translation_sigma)),
      Eigen::Vector3d::Constant(1 / (loop_rotation_sigma * loop_rotation_sigma));
  std::uniform_int_distribution<int> query_of(kKeyframesPerLap + 2, keyframes - 1);
  std::vector<int> queries;
  while (static_cast<int>(queries.size()) < loops && keyframes > kKeyframesPerLap + 2) {
    const int query = query_of(random);
    if (std::find(queries.begin(), queries.end(), query) == queries.end()) queries.push_back(query);
  }
  std::sort(queries.begin(), queries.end());
  for (const int query : queries) {
    const int laps_back = 1 + static_cast<int>(random() % (query / kKeyframesPerLap));
    const int match = query - laps_back * kKeyframesPerLap + static_cast<int>(random() % 5) - 2;
    LoopEdge loop;
    loop.query_id = query;
    loop.match_id = std::max(match, 0);
    const Eigen::Vector3d translation =
        loop_translation_sigma * Eigen::Vector3d(normal(random), normal(random), normal(random));
    const Eigen::Vector3d angles =
        loop_rotation_sigma * Eigen::Vector3d(normal(random), normal(random), normal(random));
    loop.T_match_query = scenario.truth[loop.match_id].inverse() * scenario.truth[query] *
                         SmallMotion(translation, angles);
    loop.information = information.asDiagonal();
    scenario.loops.push_back(loop);
  }
  return scenario;
}

struct PositionError {
  double rms = 0, max = 0;
};

PositionError ErrorOf(const PoseGraph& graph, const Scenario& scenario) {
  PositionError error;
  for (const auto& [id, pose] : graph.MapPoses()) {
    const double e = (pose.translation() - scenario.truth[id].translation()).norm();
    error.rms += e * e;
    error.max = std::max(error.max, e);
  }
  error.rms = std::sqrt(error.rms / std::max<std::size_t>(graph.size(), 1));
  return error;
}

double Milliseconds(std::chrono::steady_clock::duration d) {
  return std::chrono::duration<double, std::milli>(d).count();
}

double Median(std::vector<double> values) {
  std::sort(values.begin(), values.end());
  const std::size_t n = values.size();
  return n % 2 ? values[n / 2] : 0.5 * (values[n / 2 - 1] + values[n / 2]);
}

constexpr char kUsage[] =
    "usage: benchmark_pose_graph [--keyframes N] [--loops M] [--repetitions R]\n"
    "Times the pose graph on a simulated run of N keyframes (default 1000) with M loop edges\n"
    "(default 50), R times (default 7): batch and incremental optimisation, error before and\n"
    "after. Prints the figures of docs/benchmarks.md.\n";

int Fail(const std::string& message) {
  std::fprintf(stderr, "benchmark_pose_graph: %s\n%s", message.c_str(), kUsage);
  return 2;
}

// A whole number of at least `minimum` from --name (or the fallback).
int WholeNumber(const stereo_fabmap_slam::tools::CommandLine& args, const std::string& name,
                int fallback, int minimum) {
  const double value = args.NumberOr(name, fallback);
  if (value != static_cast<double>(static_cast<int>(value)) || value < minimum) {
    throw std::invalid_argument("--" + name +
                                " must be a whole number >= " + std::to_string(minimum));
  }
  return static_cast<int>(value);
}

}  // namespace

int main(int argc, char** argv) {
  int keyframes = 1000, loops = 50, repetitions = 7;
  try {
    const stereo_fabmap_slam::tools::CommandLine args(
        argc, argv, {"keyframes", "loops", "repetitions"}, {"help"});
    if (args.Flag("help")) {
      std::fputs(kUsage, stdout);
      return 0;
    }
    if (!args.positional().empty()) throw std::invalid_argument("no positional arguments");
    keyframes = WholeNumber(args, "keyframes", keyframes, 1);
    loops = WholeNumber(args, "loops", loops, 0);
    repetitions = WholeNumber(args, "repetitions", repetitions, 1);
  } catch (const std::invalid_argument& error) {
    return Fail(error.what());
  }
  if (loops > keyframes - kKeyframesPerLap - 2) return Fail("too few keyframes for the loops");

  std::mt19937 random(42);
  const Scenario scenario = MakeScenario(keyframes, loops, random);
  const PoseGraphOptions options;
  std::printf("pose graph: %d keyframes, %zu loop edges, %d repetitions\n", keyframes,
              scenario.loops.size(), repetitions);

  // Batch: every loop at once from the odometry poses.
  std::vector<double> times;
  PoseGraphSummary summary;
  PositionError before, after;
  for (int r = 0; r < repetitions; ++r) {
    PoseGraph graph(options);
    for (int i = 0; i < keyframes; ++i) graph.AddKeyframe(i, scenario.odometry[i], false);
    for (const LoopEdge& loop : scenario.loops) graph.AddLoop(loop);
    before = ErrorOf(graph, scenario);
    const auto start = std::chrono::steady_clock::now();
    summary = graph.Optimize();
    times.push_back(Milliseconds(std::chrono::steady_clock::now() - start));
    after = ErrorOf(graph, scenario);
  }
  std::printf(
      "batch:       median %.1f ms, max %.1f ms; %d iterations (%s), cost %.4g -> %.4g;\n"
      "             position error rms %.3f m max %.3f m before, rms %.3f m max %.3f m after\n",
      Median(times), *std::max_element(times.begin(), times.end()), summary.iterations,
      summary.converged ? "converged" : "not converged", summary.initial_cost, summary.final_cost,
      before.rms, before.max, after.rms, after.max);

  // Incremental: keyframes arrive, each loop is added when its query arrives and optimised.
  times.clear();
  std::vector<int> iterations;
  PoseGraph graph(options);
  std::size_t next_loop = 0;
  for (int i = 0; i < keyframes; ++i) {
    graph.AddKeyframe(i, scenario.odometry[i], false);
    bool closed = false;
    while (next_loop < scenario.loops.size() && scenario.loops[next_loop].query_id == i) {
      graph.AddLoop(scenario.loops[next_loop++]);
      closed = true;
    }
    if (!closed) continue;
    const auto start = std::chrono::steady_clock::now();
    summary = graph.Optimize();
    times.push_back(Milliseconds(std::chrono::steady_clock::now() - start));
    iterations.push_back(summary.iterations);
  }
  after = ErrorOf(graph, scenario);
  if (!times.empty()) {
    std::printf(
        "incremental: %zu optimisations, median %.1f ms, max %.1f ms, last %.1f ms; iterations "
        "median %.0f max %d;\n             last cost %.4g; position error rms %.3f m max %.3f m\n",
        times.size(), Median(times), *std::max_element(times.begin(), times.end()), times.back(),
        Median(std::vector<double>(iterations.begin(), iterations.end())),
        *std::max_element(iterations.begin(), iterations.end()), summary.final_cost, after.rms,
        after.max);
  }
  return 0;
}
