#include "stereo_fabmap_slam/dense/dense_mapping_worker.h"

#include <exception>
#include <stdexcept>

#include <pthread.h>
#include <sched.h>
#include <sys/resource.h>
#include <sys/syscall.h>
#include <unistd.h>

namespace stereo_fabmap_slam::dense {
namespace {

const DenseWorkerOptions& Validated(const DenseWorkerOptions& options) {
  if (!(options.view_rate > 0))
    throw std::invalid_argument("the dense map's view rate must be > 0");
  return options;
}

}  // namespace

DenseMappingWorker::DenseMappingWorker(const DenseMappingOptions& mapping,
                                       const StereoDepthOptions& depth, const FusionOptions& fusion,
                                       const camera::StereoRectifier& rectifier,
                                       const DenseWorkerOptions& options,
                                       DenseWorkerListener listener)
    : options_(Validated(options)),
      listener_(std::move(listener)),
      view_period_(1.0 / options.view_rate),
      stage_(mapping, depth, fusion, rectifier) {
  if (options_.own_thread) thread_ = std::thread(&DenseMappingWorker::Work, this);
}

DenseMappingWorker::~DenseMappingWorker() { Stop(); }

void DenseMappingWorker::Push(DenseInput input) { inputs_.Push(std::move(input)); }

void DenseMappingWorker::StepNow() {
  if (options_.own_thread) throw std::logic_error("the dense mapping worker steps on its thread");
  StepWith(inputs_.TakeRemaining());
}

void DenseMappingWorker::Finish() {
  inputs_.Stop();
  if (thread_.joinable()) thread_.join();
  // The end of a run: what came last, and every keyframe the map moved at its final pose.
  while (StepWith(inputs_.TakeRemaining())) {
  }
}

void DenseMappingWorker::Stop() {
  if (stopped_) return;
  stopped_ = true;
  inputs_.Stop();
  if (thread_.joinable()) thread_.join();
  if (options_.save_mesh_at_stop.empty()) return;
  std::lock_guard<std::mutex> lock(stage_mutex_);
  try {
    const Mesh mesh = stage_.SaveMesh(options_.save_mesh_at_stop);
    if (listener_.saved) {
      listener_.saved("wrote " + options_.save_mesh_at_stop + ": " +
                          std::to_string(mesh.vertices.size()) + " vertices of " +
                          std::to_string(stage_.volume().keyframes()) + " keyframes",
                      true);
    }
  } catch (const std::exception& error) {
    if (listener_.saved) listener_.saved(options_.save_mesh_at_stop + ": " + error.what(), false);
  }
}

double DenseMappingWorker::busy_seconds() const {
  std::lock_guard<std::mutex> lock(stage_mutex_);
  return busy_seconds_;
}

void DenseMappingWorker::Work() {
  // Below the other stages: Linux schedules each thread on its own. SCHED_IDLE runs the worker
  // only on time nothing else wants (CFS gives it the weight of 3 against 1024 for a normal
  // thread, and 15 at nice 19), which any thread may ask for. Measured in the graph on the MH01
  // bag at 1x, two runs each (docs/benchmarks.md): tracking per pair median / mean 7.69 / 7.61
  // and 7.37 / 7.40 ms without the DenseMapper, 7.59 / 7.91 and 7.76 / 8.28 ms with it at nice
  // 10, 7.31 / 7.68 and 7.37 / 7.57 ms at SCHED_IDLE, which fused as fast (41.5 against 42.6-44.8
  // ms a keyframe): the cores' idle time is enough for it. nice 19 where SCHED_IDLE is refused.
  // Not being able to lower the priority costs the tracker time, not correctness, so the
  // worker goes on after saying so.
  sched_param idle{};
  idle.sched_priority = 0;
  if (pthread_setschedparam(pthread_self(), SCHED_IDLE, &idle) != 0 &&
      setpriority(PRIO_PROCESS, static_cast<id_t>(syscall(SYS_gettid)), 19) != 0 &&
      listener_.failed) {
    std::lock_guard<std::mutex> lock(stage_mutex_);
    listener_.failed("could not lower the dense mapping thread's priority");
  }
  bool busy = false;  // the stage has work left: take what came meanwhile and go on at once
  while (auto inputs = inputs_.TakeAll(busy ? std::chrono::duration<double>(0) : view_period_)) {
    try {
      busy = StepWith(std::move(*inputs));
    } catch (const std::exception& error) {  // Open3D out of memory: the map stays as it was
      std::lock_guard<std::mutex> lock(stage_mutex_);
      if (listener_.failed) listener_.failed(error.what());
      busy = false;  // not at once again: the next inputs, or the next period, try once more
    }
  }
}

bool DenseMappingWorker::StepWith(std::deque<DenseInput> inputs) {
  std::lock_guard<std::mutex> lock(stage_mutex_);
  const auto start = std::chrono::steady_clock::now();  // not the wait for the lock
  for (DenseInput& input : inputs) stage_.Add(std::move(input));
  const DenseStepReport report = stage_.Step();
  if (listener_.report) listener_.report(report);
  const auto now = std::chrono::steady_clock::now();
  if (listener_.view && stage_.view_changed() &&
      (!last_view_ || now - *last_view_ >= view_period_)) {
    last_view_ = now;  // first: a view that throws is not tried again at once
    if (listener_.view(stage_)) stage_.ViewSent();
  }
  busy_seconds_ += std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return stage_.busy();
}

}  // namespace stereo_fabmap_slam::dense
