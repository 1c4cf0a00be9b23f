#pragma once

#include <algorithm>
#include <cstddef>
#include <deque>
#include <optional>
#include <stdexcept>
#include <utility>

namespace stereo_fabmap_slam::odometry {

// Between a camera and a tracker that may be slower than it (a bag played faster than real time,
// a busy machine): frames wait here, at most `capacity` of them, and a full queue drops the
// newest, so what is queued stays a contiguous stretch of the stream. The tracker then takes
// frames so that the time between the frames it tracks stays short and even: the newest queued
// frame at most `catch_up_gap` after the last one taken, or a quarter of the backlog when that is
// longer, skipping the frames in between. A tracker that simply took the oldest frame would
// track the frame after a slow one with a short gap and then jump over everything that arrived
// meanwhile; the motion model predicts badly across such a jump, the search by descriptor it
// then needs is slow, and the next jump is longer still (issue 14: a tracking loss in 5 of 24
// runs of MH01 at 5x real time, none with this queue).
//
// The quarter: with r frames arriving per tracked frame, the backlog settles where a quarter of
// it is r frames, so the gaps equal r frames (as even as the tracker's speed allows) and a queue
// of 16 absorbs a tracker up to 4 times slower than the camera before it drops frames unseen.
//
// Not thread-safe: the camera's thread and the tracker's share it under their own lock.
template <typename Frame>
class FrameQueue {
 public:
  struct Taken {
    Frame frame;
    double stamp = 0;
    std::size_t skipped = 0;  // queued frames passed over to reach it
  };

  // capacity >= 1; catch_up_gap [s] >= 0 (0: every frame while the backlog is short).
  FrameQueue(std::size_t capacity, double catch_up_gap)
      : capacity_(capacity), catch_up_gap_(catch_up_gap) {
    if (capacity < 1) throw std::invalid_argument("FrameQueue: capacity must be >= 1");
    if (!(catch_up_gap >= 0)) throw std::invalid_argument("FrameQueue: catch_up_gap must be >= 0");
  }

  // Queues a frame with its stamp [s]; false when the queue is full (the frame is dropped).
  bool Push(double stamp, Frame frame) {
    if (frames_.size() >= capacity_) return false;
    frames_.emplace_back(stamp, std::move(frame));
    return true;
  }

  bool empty() const { return frames_.empty(); }
  std::size_t size() const { return frames_.size(); }

  // The next frame to track, removed with the frames before it. Requires !empty(). The first
  // frame, a frame after a gap longer than the step, and the first frame after time went
  // backwards (a bag played again) are taken as they come: nothing is skipped across them.
  Taken Take() {
    if (frames_.empty()) throw std::logic_error("FrameQueue::Take on an empty queue");
    std::size_t index = 0;
    if (last_taken_ && frames_.front().first >= *last_taken_) {
      std::size_t contiguous = 1;  // stamps that keep increasing from the front
      while (contiguous < frames_.size() &&
             frames_[contiguous].first >= frames_[contiguous - 1].first) {
        ++contiguous;
      }
      const double backlog = frames_[contiguous - 1].first - *last_taken_;
      const double step = std::max(catch_up_gap_, backlog / kBacklogDivisor);
      for (std::size_t i = 1;
           i < contiguous && frames_[i].first - *last_taken_ <= step + kStampJitter; ++i) {
        index = i;
      }
    }
    Taken taken{std::move(frames_[index].second), frames_[index].first, index};
    frames_.erase(frames_.begin(), frames_.begin() + static_cast<std::ptrdiff_t>(index) + 1);
    last_taken_ = taken.stamp;
    return taken;
  }

 private:
  static constexpr double kBacklogDivisor = 4;  // the quarter above
  // [s] A camera's stamps jitter about its period: in EuRoC each frame by +-128 ns (two frames
  // at 20 Hz are 99,999,744-100,000,256 ns apart), with USB cameras by a millisecond or two.
  // A stamp of 1.4e9 s held in a double resolves only 0.24 us besides. Without this, "at most
  // 0.1 s" would take every frame half the time. 5 ms is below the period of any camera slower
  // than 200 Hz.
  static constexpr double kStampJitter = 0.005;

  std::size_t capacity_;
  double catch_up_gap_;
  std::deque<std::pair<double, Frame>> frames_;
  std::optional<double> last_taken_;
};

}  // namespace stereo_fabmap_slam::odometry
