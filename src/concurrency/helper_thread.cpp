#include "stereo_fabmap_slam/concurrency/helper_thread.h"

#include <exception>

namespace stereo_fabmap_slam::concurrency {

struct HelperThread::Job {
  const std::function<void(int)>* piece = nullptr;
  int count = 0;
  std::atomic<int> next{0};
  std::atomic<bool> helper_done{false};
  std::mutex error_mutex;
  std::exception_ptr error;  // the first piece's exception, guarded by error_mutex
};

namespace {

// Marks the helper as taken by one caller for the caller's scope; a second caller (or a piece
// that calls ForEachPiece again) finds it taken and runs alone.
class Claim {
 public:
  explicit Claim(std::atomic<bool>* taken) : taken_(taken), owned_(!taken->exchange(true)) {}
  ~Claim() {
    if (owned_) taken_->store(false);
  }
  Claim(const Claim&) = delete;
  Claim& operator=(const Claim&) = delete;
  bool owned() const { return owned_; }

 private:
  std::atomic<bool>* taken_;
  bool owned_;
};

}  // namespace

HelperThread::HelperThread(std::chrono::microseconds spin)
    : spin_(spin), thread_(&HelperThread::Work, this) {}

HelperThread::~HelperThread() {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    stopping_ = true;
  }
  wake_.notify_one();
  thread_.join();
}

void HelperThread::TakePieces(Job* job) {
  for (int i = job->next.fetch_add(1); i < job->count; i = job->next.fetch_add(1)) {
    try {
      (*job->piece)(i);
    } catch (...) {
      std::lock_guard<std::mutex> lock(job->error_mutex);
      if (!job->error) job->error = std::current_exception();
      job->next.store(job->count);  // the pieces not started yet are left out
    }
  }
}

void HelperThread::ForEachPiece(int count, const std::function<void(int)>& piece) {
  if (count <= 0) return;
  Job job;
  job.piece = &piece;
  job.count = count;
  const Claim claim(&taken_);
  const bool share = claim.owned() && count > 1 && std::this_thread::get_id() != thread_.get_id();
  if (share) {
    offered_.store(&job);
    std::lock_guard<std::mutex> lock(mutex_);
    if (sleeping_) wake_.notify_one();
  }
  TakePieces(&job);
  if (share) {
    Job* expected = &job;
    if (!offered_.compare_exchange_strong(expected, nullptr)) {
      // The helper took the job: it may still be in a piece, and must leave the job (on this
      // stack) before we return.
      while (!job.helper_done.load(std::memory_order_acquire)) std::this_thread::yield();
    }
  }
  if (job.error) std::rethrow_exception(job.error);
}

void HelperThread::Work() {
  for (;;) {
    Job* job = nullptr;
    const auto idle_since = std::chrono::steady_clock::now();
    while (job == nullptr) {
      Job* offered = offered_.load();
      if (offered != nullptr) {
        // Taken back by the caller in the meantime if this fails: look again.
        if (offered_.compare_exchange_strong(offered, nullptr)) job = offered;
        continue;
      }
      if (std::chrono::steady_clock::now() - idle_since < spin_) {
        // yield(), not a pause loop: another thread that wants this core gets it at once.
        std::this_thread::yield();
        continue;
      }
      std::unique_lock<std::mutex> lock(mutex_);
      sleeping_ = true;
      wake_.wait(lock, [&] { return stopping_ || offered_.load() != nullptr; });
      sleeping_ = false;
      if (stopping_) return;
    }
    TakePieces(job);
    job->helper_done.store(true, std::memory_order_release);  // the job is not touched again
  }
}

}  // namespace stereo_fabmap_slam::concurrency
