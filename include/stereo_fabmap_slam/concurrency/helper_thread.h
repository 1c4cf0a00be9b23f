#pragma once

// A second thread for the front end's per-frame work (rectification, detection, description,
// stereo matching, the search of the map points): each stage splits its work into pieces and the
// calling thread and this one take pieces until none are left.

#include <atomic>
#include <chrono>
#include <condition_variable>
#include <functional>
#include <mutex>
#include <thread>

namespace stereo_fabmap_slam::concurrency {

// Why not std::async, OpenCV's parallel_for_ or TBB (docs/benchmarks.md, "A front end under 5
// ms"): std::async starts a thread per call, 50-70 us on a 2-core virtual machine, as
// long as half of a 100 us task; OpenCV runs every parallel_for_ serially while any other
// thread of the process is inside one (a process-wide flag), so in the nodelet manager the
// dense mapper's fusion would take the tracker's second core away; and a thread pool's worker
// that sleeps between frames costs the same wake-up as a new thread. This thread stays awake
// for `spin` after each piece of work (the stages of a frame follow one another closely, so
// only the frame's first stage pays the wake-up) and then sleeps on a condition variable.
//
// Pieces are taken from a shared counter, so the work balances itself, and when the helper is
// busy or slow to wake (the other core running the bundle adjustment, say) the caller takes
// every piece itself: never slower than one thread by more than the hand-over.
class HelperThread {
 public:
  explicit HelperThread(std::chrono::microseconds spin = std::chrono::microseconds(300));
  ~HelperThread();
  HelperThread(const HelperThread&) = delete;
  HelperThread& operator=(const HelperThread&) = delete;

  // Calls piece(i) once for each i in [0, count), on this thread and the calling one, and
  // returns when every call has returned. The first exception a piece throws is thrown here
  // (pieces not started yet are then left out). Callers may call from several threads: one
  // at a time gets the helper, the others run their pieces alone.
  void ForEachPiece(int count, const std::function<void(int)>& piece);

 private:
  struct Job;
  void Work();
  static void TakePieces(Job* job);

  const std::chrono::microseconds spin_;
  std::atomic<bool> taken_{false};  // by the caller whose job the helper may take
  std::atomic<Job*> offered_{nullptr};
  std::mutex mutex_;
  std::condition_variable wake_;
  bool sleeping_ = false;  // guarded by mutex_
  bool stopping_ = false;  // guarded by mutex_
  std::thread thread_;     // last: starts after the members it uses exist
};

}  // namespace stereo_fabmap_slam::concurrency
