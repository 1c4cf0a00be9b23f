#pragma once

#include <chrono>
#include <functional>
#include <mutex>
#include <optional>
#include <string>
#include <thread>
#include <utility>

#include "stereo_fabmap_slam/concurrency/arrival_queue.h"
#include "stereo_fabmap_slam/dense/dense_mapping_stage.h"

namespace stereo_fabmap_slam::dense {

struct DenseWorkerOptions {
  // A thread of its own (the DenseMapper nodelet, run_dataset --dense --threads), or the
  // caller's (run_dataset --dense: the same map from the same run every time).
  bool own_thread = true;
  // [Hz] at most, of the view (the nodelet's dense_cloud and dense_mesh) while the map changes;
  // also how long the thread waits for inputs when the stage has nothing to do.
  double view_rate = 0.5;
  // A PLY file the mesh is written to when the worker stops ("" for none): the nodelet's
  // ~save_mesh, what a graph that is shut down leaves behind.
  std::string save_mesh_at_stop;
};

// What the worker tells its driver; each may be left empty. Called one at a time, on the worker's
// thread (or the caller's, without one), with the stage locked.
struct DenseWorkerListener {
  std::function<void(const DenseStepReport&)> report;  // every step's
  // The map's view changed and the last was offered at least 1 / view_rate ago: send it (a
  // cloud, a mesh) and return true, or false if nobody wants it now (it is offered again with
  // the next change).
  std::function<bool(const DenseMappingStage&)> view;
  // A step or the view on the worker's own thread failed (Open3D out of memory: the map stays
  // as it was), or its priority could not be lowered.
  std::function<void(const std::string& what)> failed;
  // What the save at stop wrote, or why it failed.
  std::function<void(const std::string& message, bool success)> saved;
};

// The dense mapping stage's driver, the same for the graph and offline (docs/architecture.md):
// the inputs in arrival order, handed to the stage all at once, then one step; with a thread of
// its own that thread runs below the other stages' priority (on two cores the tracker must not
// wait for the dense map) and goes on at once while the stage is busy (keyframes the map moved
// wait), else waits for inputs at most 1 / view_rate; the view offered at most at view_rate
// when it changed; at the end of a run, steps until every moved keyframe is fused again; the
// mesh saved when it stops. Thread-safe: any thread may Push and read the stage (WithStage).
class DenseMappingWorker {
 public:
  // The stage made of the first four; throws std::invalid_argument for invalid options (a
  // view_rate that is not > 0, or the stage's).
  DenseMappingWorker(const DenseMappingOptions& mapping, const StereoDepthOptions& depth,
                     const FusionOptions& fusion, const camera::StereoRectifier& rectifier,
                     const DenseWorkerOptions& options, DenseWorkerListener listener);
  ~DenseMappingWorker();  // Stop()
  DenseMappingWorker(const DenseMappingWorker&) = delete;
  DenseMappingWorker& operator=(const DenseMappingWorker&) = delete;

  // The inputs, in the order they come.
  void Push(DenseInput input);
  // Without a thread of its own: hands what was pushed to the stage and steps once (what
  // run_dataset does after each frame). Throws std::logic_error with one.
  void StepNow();
  // The end of a run: the thread joined, what waits handed over, then steps until the stage is
  // no longer busy. Throws what the stage throws (Open3D out of memory).
  void Finish();
  // Stops the thread (what waits is dropped: a graph being shut down) and saves the mesh if
  // asked to (once; later calls do nothing).
  void Stop();

  // f(const DenseMappingStage&) with the stage locked (the save services, a summary).
  template <typename Read>
  auto WithStage(Read&& read) const {
    std::lock_guard<std::mutex> lock(stage_mutex_);
    return read(static_cast<const DenseMappingStage&>(stage_));
  }
  // Seconds the worker spent on the stage, steps and view (not waiting).
  double busy_seconds() const;

 private:
  void Work();
  // One step with what came; the view if due. Returns whether the stage is still busy.
  bool StepWith(std::deque<DenseInput> inputs);

  const DenseWorkerOptions options_;
  const DenseWorkerListener listener_;
  const std::chrono::duration<double> view_period_;

  mutable std::mutex stage_mutex_;  // the stage, the view's time, busy_seconds_
  DenseMappingStage stage_;
  std::optional<std::chrono::steady_clock::time_point> last_view_;  // none offered yet
  double busy_seconds_ = 0;

  concurrency::ArrivalQueue<DenseInput> inputs_;
  bool stopped_ = false;  // Stop's: the thread's owner's only
  std::thread thread_;    // last: starts after the members it uses exist
};

}  // namespace stereo_fabmap_slam::dense
