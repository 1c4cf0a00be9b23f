#include "stereo_fabmap_slam/pipeline/serial_worker.h"

#include <stdexcept>
#include <utility>

namespace stereo_fabmap_slam::pipeline {

SerialWorker::SerialWorker(std::size_t capacity) : capacity_(capacity) {
  if (capacity_ == 0) throw std::invalid_argument("SerialWorker: the queue needs room for a job");
  thread_ = std::thread([this] { Run(); });
}

SerialWorker::~SerialWorker() {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    stopping_ = true;
  }
  changed_.notify_all();
  thread_.join();
}

void SerialWorker::Submit(std::function<void()> job) {
  std::unique_lock<std::mutex> lock(mutex_);
  changed_.wait(lock, [this] { return queue_.size() < capacity_; });
  RethrowLocked(lock);
  queue_.push_back(std::move(job));
  lock.unlock();
  changed_.notify_all();
}

void SerialWorker::WaitIdle() {
  std::unique_lock<std::mutex> lock(mutex_);
  changed_.wait(lock, [this] { return queue_.empty() && !running_job_; });
  RethrowLocked(lock);
}

void SerialWorker::RethrowLocked(std::unique_lock<std::mutex>& lock) {
  if (!error_) return;
  std::exception_ptr error = std::exchange(error_, nullptr);
  lock.unlock();
  std::rethrow_exception(error);
}

void SerialWorker::Run() {
  std::unique_lock<std::mutex> lock(mutex_);
  while (true) {
    changed_.wait(lock, [this] { return stopping_ || !queue_.empty(); });
    if (queue_.empty()) return;  // stopping, and nothing left to run
    std::function<void()> job = std::move(queue_.front());
    queue_.pop_front();
    running_job_ = true;
    lock.unlock();
    changed_.notify_all();  // room in the queue
    std::exception_ptr error;
    try {
      job();
    } catch (...) {
      error = std::current_exception();
    }
    lock.lock();
    running_job_ = false;
    if (error && !error_) error_ = error;
    changed_.notify_all();
  }
}

}  // namespace stereo_fabmap_slam::pipeline
