#pragma once

#include <condition_variable>
#include <cstddef>
#include <deque>
#include <exception>
#include <functional>
#include <mutex>
#include <thread>

namespace stereo_fabmap_slam::pipeline {

// One thread that runs jobs one after another in the order they were submitted, with a bounded
// queue: Submit waits while `capacity` jobs wait to run, so a producer faster than the jobs is
// slowed down, never lets the queue grow without bound. The thread is started by the constructor
// and joined by the destructor after the queue has run out. A job's exception is kept and
// thrown again by the next Submit or WaitIdle (the jobs after it still run).
class SerialWorker {
 public:
  explicit SerialWorker(std::size_t capacity);
  ~SerialWorker();
  SerialWorker(const SerialWorker&) = delete;
  SerialWorker& operator=(const SerialWorker&) = delete;

  void Submit(std::function<void()> job);
  // Returns when every job submitted so far has run.
  void WaitIdle();

 private:
  void Run();
  void RethrowLocked(std::unique_lock<std::mutex>& lock);

  const std::size_t capacity_;
  std::mutex mutex_;
  std::condition_variable changed_;
  std::deque<std::function<void()>> queue_;
  bool running_job_ = false;
  bool stopping_ = false;
  std::exception_ptr error_;
  std::thread thread_;  // last: starts after the members it uses exist
};

}  // namespace stereo_fabmap_slam::pipeline
