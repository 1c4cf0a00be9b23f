#pragma once

// A worker thread's inputs, as callbacks (or a driver's loop) push them: the Backend's and the
// dense mapping worker's (dense/dense_mapping_worker.h).

#include <chrono>
#include <condition_variable>
#include <deque>
#include <mutex>
#include <optional>
#include <utility>

namespace stereo_fabmap_slam::concurrency {

// The inputs waiting for a worker, in arrival order, handed over all at once. Never bounded by
// dropping: what a stage takes is its to bound (a keyframe missing from the map would leave a
// hole in the graph; the dense mapping stage keeps only its latest pairs).
template <typename Input>
class ArrivalQueue {
 public:
  void Push(Input input) {
    {
      std::lock_guard<std::mutex> lock(mutex_);
      inputs_.push_back(std::move(input));
    }
    wake_.notify_one();
  }
  // Waits for inputs and returns all that wait; nullopt when stopping.
  std::optional<std::deque<Input>> TakeAll() {
    std::unique_lock<std::mutex> lock(mutex_);
    wake_.wait(lock, [&] { return stopping_ || !inputs_.empty(); });
    return TakeLocked();
  }
  // The same, waiting at most `timeout` (then what waits: perhaps nothing).
  template <typename Rep, typename Period>
  std::optional<std::deque<Input>> TakeAll(std::chrono::duration<Rep, Period> timeout) {
    std::unique_lock<std::mutex> lock(mutex_);
    wake_.wait_for(lock, timeout, [&] { return stopping_ || !inputs_.empty(); });
    return TakeLocked();
  }
  // Wakes every waiting TakeAll, which returns nullopt from now on.
  void Stop() {
    {
      std::lock_guard<std::mutex> lock(mutex_);
      stopping_ = true;
    }
    wake_.notify_all();
  }
  // What waits, stopped or not, without waiting: what a worker that was stopped at the end of a
  // run still has to do.
  std::deque<Input> TakeRemaining() {
    std::lock_guard<std::mutex> lock(mutex_);
    std::deque<Input> waiting;
    waiting.swap(inputs_);
    return waiting;
  }

 private:
  std::optional<std::deque<Input>> TakeLocked() {
    if (stopping_) return std::nullopt;
    std::deque<Input> waiting;
    waiting.swap(inputs_);
    return waiting;
  }

  std::mutex mutex_;
  std::condition_variable wake_;
  std::deque<Input> inputs_;
  bool stopping_ = false;
};

}  // namespace stereo_fabmap_slam::concurrency
