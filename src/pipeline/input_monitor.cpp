#include "stereo_fabmap_slam/pipeline/input_monitor.h"

#include <algorithm>
#include <cstdio>
#include <cstring>
#include <stdexcept>

namespace stereo_fabmap_slam::pipeline {
namespace {

constexpr std::uint64_t kMostSkippedToCount = 100;
const char* const kSideNames[2] = {"left", "right"};

bool SameImage(const cv::Mat& a, const cv::Mat& b) {
  if (a.empty() || b.empty() || a.size() != b.size() || a.type() != b.type()) return false;
  for (int row = 0; row < a.rows; ++row) {
    if (std::memcmp(a.ptr(row), b.ptr(row), a.cols * a.elemSize()) != 0) return false;
  }
  return true;
}

std::string Format(const char* format, double a, double b = 0) {
  char text[256];
  std::snprintf(text, sizeof(text), format, a, b);
  return text;
}

}  // namespace

InputMonitor::InputMonitor(const InputMonitorOptions& options, std::optional<cv::Size> image_size)
    : options_(options), image_size_(image_size) {
  if (!(options.dropout_seconds > 0) || !(options.skip_report_period > 0) ||
      options.unpaired_limit < 1) {
    throw std::invalid_argument("InputMonitor: periods must be > 0 and the unpaired limit >= 1");
  }
}

void InputMonitor::SetImageSize(const cv::Size& image_size) {
  std::lock_guard<std::mutex> lock(mutex_);
  image_size_ = image_size;
}

InputMonitor::Verdict InputMonitor::CheckPair(double stamp, const cv::Mat& left,
                                              const cv::Mat& right, std::uint64_t arrival) {
  std::lock_guard<std::mutex> lock(mutex_);
  Verdict verdict;
  if (!image_size_) {
    verdict.track = false;
    ++counts_.refused;
    verdict.events.push_back({InputEvent::Kind::kUncalibrated,
                              "no calibration yet (waiting for camera_info); frame skipped", true,
                              true});
    return verdict;
  }
  if (left.size() != *image_size_ || right.size() != *image_size_) {
    verdict.track = false;
    ++counts_.refused;
    char text[160];
    std::snprintf(text, sizeof(text),
                  "image size %dx%d / %dx%d differs from the calibration's %dx%d; frame skipped",
                  left.cols, left.rows, right.cols, right.rows, image_size_->width,
                  image_size_->height);
    verdict.events.push_back({InputEvent::Kind::kWrongSize, text, true, true});
    return verdict;
  }
  // A camera that freezes sends its last image again under new stamps: tracking it would claim
  // the robot stands still. Refused, and said so, until the image changes.
  const bool later = !last_stamp_ || stamp > *last_stamp_;
  const bool left_frozen = SameImage(left, previous_left_);
  const bool right_frozen = SameImage(right, previous_right_);
  if (last_stamp_ && later && (left_frozen || right_frozen)) {
    verdict.track = false;
    ++counts_.refused;
    ++frozen_frames_;
    const char* which = left_frozen && right_frozen ? "left and right cameras are"
                        : left_frozen               ? "left camera is"
                                                    : "right camera is";
    char text[200];
    std::snprintf(text, sizeof(text),
                  "the %s frozen: the same image %d time(s) in a row under new stamps; frames "
                  "skipped until it changes",
                  which, frozen_frames_);
    verdict.events.push_back({InputEvent::Kind::kFrozen, text, true, true});
    return verdict;
  }
  if (frozen_frames_ > 0) {
    verdict.events.push_back({InputEvent::Kind::kUnfrozen,
                              "the camera images change again after " +
                                  std::to_string(frozen_frames_) + " frozen frame(s)",
                              false, false});
    frozen_frames_ = 0;
  }
  left.copyTo(previous_left_);
  right.copyTo(previous_right_);
  if (last_stamp_ && !later) {
    verdict.reset = true;
    verdict.events.push_back(
        {InputEvent::Kind::kTimeBackwards,
         Format("time went backwards (%.3f after %.3f; a looped bag?): tracking reset", stamp,
                *last_stamp_),
         true, false});
  } else if (last_stamp_ && stamp - *last_stamp_ > options_.max_prediction_gap) {
    verdict.events.push_back(
        {InputEvent::Kind::kGap,
         Format("no stereo pairs for %.1f s (a gap in the images): the motion model assumes no "
                "motion across it; a lost track relocalizes",
                stamp - *last_stamp_),
         true, false});
  }
  last_stamp_ = stamp;
  verdict.frames_skipped =
      static_cast<int>(last_tracked_arrival_ == 0 || arrival <= last_tracked_arrival_
                           ? 0
                           : std::min(arrival - last_tracked_arrival_ - 1, kMostSkippedToCount));
  last_tracked_arrival_ = arrival;
  ++counts_.tracked;
  return verdict;
}

std::vector<InputEvent> InputMonitor::OnImage(int side, double now) {
  std::lock_guard<std::mutex> lock(mutex_);
  std::vector<InputEvent> events;
  const int other = 1 - side;
  // A new stream of this side begins when its previous image is older than a dropout: after a
  // pause of both cameras (a bag played again later) the other one is not silent *while* this
  // one streams.
  if (!last_image_[side] || now - *last_image_[side] > options_.dropout_seconds) {
    stream_start_[side] = now;
  }
  last_image_[side] = now;
  ++images_[side];
  const double other_last = last_image_[other] ? *last_image_[other] : stream_start_[side];
  const double silent = now - std::max(other_last, stream_start_[side]);
  if (silent > options_.dropout_seconds) {
    dropout_reported_ = true;
    char text[200];
    std::snprintf(text, sizeof(text),
                  "no %s images for %.1f s while %s images arrive: a camera dropped out; no "
                  "stereo pairs, tracking waits for it",
                  kSideNames[other], now - other_last, kSideNames[side]);
    events.push_back({InputEvent::Kind::kDropout, text, true, true});
    return events;
  }
  // Images of this side beyond the pairs made: they found no partner. Signed: the pair is
  // counted by another callback than the image, in either order. Only while the other camera
  // streams too (an image within a quarter of the dropout time: 5 frames at 20 Hz): a camera
  // that falls silent is a dropout, said as one once it has lasted.
  const auto unpaired =
      static_cast<std::int64_t>(images_[side]) - static_cast<std::int64_t>(counts_.received);
  const bool other_streams =
      last_image_[other] && now - *last_image_[other] < 0.25 * options_.dropout_seconds;
  if (unpaired > options_.unpaired_limit && other_streams) {
    char text[200];
    std::snprintf(text, sizeof(text),
                  "left/right images do not synchronise (%lu left, %lu right, %lu pairs); stamps "
                  "must be equal, or set ~approximate_sync",
                  static_cast<unsigned long>(images_[0]), static_cast<unsigned long>(images_[1]),
                  static_cast<unsigned long>(counts_.received));
    events.push_back({InputEvent::Kind::kUnsynchronised, text, true, true});
  }
  return events;
}

std::vector<InputEvent> InputMonitor::OnPair(double /*now*/) {
  std::lock_guard<std::mutex> lock(mutex_);
  ++counts_.received;
  std::vector<InputEvent> events;
  if (dropout_reported_) {
    dropout_reported_ = false;
    events.push_back({InputEvent::Kind::kPairsAgain, "stereo pairs arrive again", false, false});
  }
  return events;
}

void InputMonitor::CountSkipped(std::uint64_t pairs) {
  std::lock_guard<std::mutex> lock(mutex_);
  counts_.skipped += pairs;
}

void InputMonitor::CountRefused() {
  std::lock_guard<std::mutex> lock(mutex_);
  ++counts_.refused;
}

bool InputMonitor::HasUnreportedSkips() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return counts_.skipped > skips_reported_;
}

double InputMonitor::NextSkipReport() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return last_skip_report_ + options_.skip_report_period;
}

InputCounts InputMonitor::counts() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return counts_;
}

std::optional<InputEvent> InputMonitor::SkipReport(double now, double last_frame_ms) {
  std::lock_guard<std::mutex> lock(mutex_);
  if (counts_.skipped <= skips_reported_ || now < last_skip_report_ + options_.skip_report_period) {
    return std::nullopt;
  }
  const std::uint64_t since_last = counts_.skipped - skips_reported_;
  skips_reported_ = counts_.skipped;
  last_skip_report_ = now;
  char text[200];
  std::snprintf(text, sizeof(text),
                "skipped %lu stereo pair(s) in the last second: the tracker was still busy (%.0f "
                "ms for its last pair); %lu skipped in all",
                static_cast<unsigned long>(since_last), last_frame_ms,
                static_cast<unsigned long>(counts_.skipped));
  return InputEvent{InputEvent::Kind::kSkipped, text, true, false};
}

}  // namespace stereo_fabmap_slam::pipeline
