// The front end's second thread (concurrency/helper_thread.h): every piece once, the two threads
// at the same time, errors passed on, a caller that finds the helper taken runs alone. That the
// stages using it give the results of one thread: features_test, stereo_rectifier_test.
#include <atomic>
#include <chrono>
#include <stdexcept>
#include <thread>
#include <vector>

#include <gtest/gtest.h>

#include "stereo_fabmap_slam/concurrency/helper_thread.h"

namespace stereo_fabmap_slam::concurrency {
namespace {

// Waits until `flag` is set, at most `limit`; true if it was.
bool WaitFor(const std::atomic<bool>& flag, std::chrono::seconds limit) {
  const auto end = std::chrono::steady_clock::now() + limit;
  while (!flag.load()) {
    if (std::chrono::steady_clock::now() > end) return false;
    std::this_thread::yield();
  }
  return true;
}

TEST(HelperThread, CallsEveryPieceExactlyOnce) {
  HelperThread helper;
  for (int count : {0, 1, 2, 7, 64, 1000}) {
    std::vector<std::atomic<int>> calls(static_cast<std::size_t>(count));
    helper.ForEachPiece(count, [&](int i) { ++calls[static_cast<std::size_t>(i)]; });
    for (int i = 0; i < count; ++i) EXPECT_EQ(calls[static_cast<std::size_t>(i)].load(), 1) << i;
  }
}

TEST(HelperThread, RunsTwoPiecesAtTheSameTime) {
  // The first piece cannot end before the second has started: the caller takes piece 0 and
  // holds it, so piece 1 can only start on the helper. A helper that did not take work would
  // time out here (the bound only guards against a hang; it takes microseconds).
  HelperThread helper;
  std::atomic<bool> second_started{false};
  std::atomic<bool> first_saw_second{false};
  std::thread::id first_thread, second_thread;
  helper.ForEachPiece(2, [&](int piece) {
    if (piece == 0) {
      first_thread = std::this_thread::get_id();
      first_saw_second = WaitFor(second_started, std::chrono::seconds(10));
    } else {
      second_thread = std::this_thread::get_id();
      second_started = true;
    }
  });
  EXPECT_TRUE(first_saw_second);
  EXPECT_NE(first_thread, second_thread);
}

TEST(HelperThread, WakesAfterSleepingAndStillShares) {
  // Longer than the spin: the helper sleeps on its condition variable and must be woken.
  HelperThread helper(std::chrono::microseconds(100));
  for (int round = 0; round < 3; ++round) {
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
    std::atomic<bool> second_started{false};
    bool first_saw_second = false;
    helper.ForEachPiece(2, [&](int piece) {
      if (piece == 0) {
        first_saw_second = WaitFor(second_started, std::chrono::seconds(10));
      } else {
        second_started = true;
      }
    });
    EXPECT_TRUE(first_saw_second) << "round " << round;
  }
}

TEST(HelperThread, PassesOnThePiecesException) {
  HelperThread helper;
  std::atomic<int> calls{0};
  EXPECT_THROW(helper.ForEachPiece(100,
                                   [&](int i) {
                                     ++calls;
                                     if (i == 3) throw std::runtime_error("piece 3");
                                   }),
               std::runtime_error);
  // The pieces after the failure need not run, and the helper is usable again.
  EXPECT_LE(calls.load(), 100);
  std::atomic<int> again{0};
  helper.ForEachPiece(10, [&](int) { ++again; });
  EXPECT_EQ(again.load(), 10);
}

TEST(HelperThread, ANestedCallAndASecondCallerRunAlone) {
  HelperThread helper;
  // Nested: a piece that splits its own work again gets no helper (it is busy) and runs its
  // pieces itself, without deadlock.
  std::atomic<int> inner{0};
  helper.ForEachPiece(4, [&](int) { helper.ForEachPiece(5, [&](int) { ++inner; }); });
  EXPECT_EQ(inner.load(), 20);
  // Two callers at once: each completes its own pieces.
  std::atomic<int> a{0}, b{0};
  std::thread other([&] {
    for (int k = 0; k < 200; ++k) helper.ForEachPiece(8, [&](int) { ++b; });
  });
  for (int k = 0; k < 200; ++k) helper.ForEachPiece(8, [&](int) { ++a; });
  other.join();
  EXPECT_EQ(a.load(), 1600);
  EXPECT_EQ(b.load(), 1600);
}

}  // namespace
}  // namespace stereo_fabmap_slam::concurrency
