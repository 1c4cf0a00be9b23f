// The worker that runs the mapping beside the tracking (StereoSlam::EnableConcurrentMapping):
// jobs in order, a bounded queue, errors passed on, nothing left running at destruction.
#include <atomic>
#include <chrono>
#include <stdexcept>
#include <thread>
#include <vector>

#include <gtest/gtest.h>

#include "stereo_fabmap_slam/pipeline/serial_worker.h"

namespace stereo_fabmap_slam::pipeline {
namespace {

TEST(SerialWorker, RunsJobsInTheOrderSubmittedAndWaitIdleSeesThemAll) {
  std::vector<int> order;  // written by the worker only; read after WaitIdle
  SerialWorker worker(3);
  for (int i = 0; i < 50; ++i) worker.Submit([&order, i] { order.push_back(i); });
  worker.WaitIdle();
  ASSERT_EQ(order.size(), 50u);
  for (int i = 0; i < 50; ++i) EXPECT_EQ(order[static_cast<std::size_t>(i)], i);
}

TEST(SerialWorker, SubmitWaitsWhileTheQueueIsFull) {
  // The first job holds the worker until released. Whether or not the worker has taken it off
  // the queue yet, a queue of two then has room for at most two more jobs: the fourth Submit
  // cannot return before the first job ends.
  std::atomic<bool> release{false}, fourth_submitted{false};
  std::atomic<int> ran{0};
  const auto count = [&ran] { ++ran; };
  SerialWorker worker(2);
  worker.Submit([&release] {
    while (!release) std::this_thread::yield();
  });
  worker.Submit(count);
  std::thread producer([&] {
    worker.Submit(count);
    worker.Submit(count);
    fourth_submitted = true;
  });
  std::this_thread::sleep_for(std::chrono::milliseconds(100));
  EXPECT_FALSE(fourth_submitted);
  release = true;
  producer.join();
  worker.WaitIdle();
  EXPECT_TRUE(fourth_submitted);
  EXPECT_EQ(ran, 3);
}

TEST(SerialWorker, AJobsExceptionReachesTheCallerAndLaterJobsStillRun) {
  SerialWorker worker(4);
  bool later_ran = false;
  worker.Submit([] { throw std::runtime_error("job failed"); });
  worker.Submit([&later_ran] { later_ran = true; });
  EXPECT_THROW(worker.WaitIdle(), std::runtime_error);
  EXPECT_TRUE(later_ran);
  EXPECT_NO_THROW(worker.WaitIdle());  // reported once
  EXPECT_THROW(SerialWorker(0), std::invalid_argument);
}

TEST(SerialWorker, DestructionRunsWhatWasQueued) {
  std::atomic<int> ran{0};
  {
    SerialWorker worker(8);
    for (int i = 0; i < 8; ++i)
      worker.Submit([&ran] {
        std::this_thread::sleep_for(std::chrono::milliseconds(1));
        ++ran;
      });
  }
  EXPECT_EQ(ran, 8);
}

}  // namespace
}  // namespace stereo_fabmap_slam::pipeline
