#pragma once

#include <cstdint>
#include <mutex>
#include <optional>
#include <string>
#include <vector>

#include <opencv2/core.hpp>

namespace stereo_fabmap_slam::pipeline {

// Something about the camera input (or what tracking made of it) the user should hear of; the
// driver logs it.
struct InputEvent {
  enum class Kind {
    kTrackingLost,    // a frame not tracked (the drivers say it)
    kTrackingFound,   // tracking found its map again after lost frames (the drivers say it)
    kUnreadable,      // a message the driver could not make an image of: refused (CountRefused)
    kUncalibrated,    // a pair before the camera's calibration is known: refused
    kWrongSize,       // a pair of another size than the calibration's: refused
    kFrozen,          // the same image again under a new stamp: refused
    kUnfrozen,        // the images change again
    kTimeBackwards,   // a stamp not after the last one (a looped bag): tracking starts afresh
    kGap,             // no pairs for longer than the motion model bridges
    kDropout,         // one camera silent while the other streams
    kPairsAgain,      // stereo pairs arrive again after a dropout
    kUnsynchronised,  // images of the two cameras do not pair up
    kSkipped,         // pairs the tracker had no time for
  };
  Kind kind;
  std::string message;
  bool warning = true;  // false: good news (kUnfrozen, kPairsAgain)
  // A message that repeats while the condition lasts: log it throttled (kFrozen,
  // kUnsynchronised, kDropout, kWrongSize, kUncalibrated).
  bool repeats = false;
};

struct InputMonitorOptions {
  double max_prediction_gap = 0.5;  // [s] tracker/max_prediction_gap: a longer gap is named
  // [s] A camera silent this long while the other one streams has dropped out: at 20 Hz that is
  // 20 frames, far beyond any jitter or a dropped message.
  double dropout_seconds = 1.0;
  // Images of one side beyond the pairs made of them by more than this (the synchroniser's
  // queue) do not pair up: stamps differ, or approximate sync is needed.
  int unpaired_limit = 10;
  // Pairs skipped are reported at most once in this long [s].
  double skip_report_period = 1.0;
};

// What the pairs of a run came to.
struct InputCounts {
  std::uint64_t received = 0;  // stereo pairs the driver was given
  std::uint64_t tracked = 0;   // handed to the tracker
  std::uint64_t refused = 0;   // bad input (wrong size, frozen) or before the calibration
  std::uint64_t skipped = 0;   // passed over for lack of time (CountSkipped)
};

// The tracking stage's watch on its input: every fault a camera or a bag can have, counted and
// named, so that no driver has to know them. Pairs: size, frozen cameras, time going backwards,
// gaps, pairs passed over (CheckPair). Single images: a camera that dropped out, cameras that do
// not synchronise (OnImage, OnPair; those are about the arrival of messages and take the wall
// time, which the monitor never reads itself). Thread-safe: a driver's image callbacks and its
// tracking thread call it at once.
class InputMonitor {
 public:
  // Without `image_size` (a driver whose calibration comes with the images, as camera_info),
  // every pair is refused until SetImageSize; the image callbacks' side works from the start, so
  // that every pair received is counted.
  explicit InputMonitor(const InputMonitorOptions& options,
                        std::optional<cv::Size> image_size = std::nullopt);
  void SetImageSize(const cv::Size& image_size);

  struct Verdict {
    bool track = true;   // false: refused (an event says why)
    bool reset = false;  // time went backwards: the tracker starts afresh
    // Pairs received between the last tracked one and this one (Tracker::Track's
    // frames_skipped), at most 100: beyond a few the keyframe look-ahead spans a whole gap.
    int frames_skipped = 0;
    std::vector<InputEvent> events;
  };
  // A stereo pair about to be tracked: raw images, its stamp [s] and `arrival`, its place in the
  // stream of pairs (1, 2, ...: pairs passed over leave gaps).
  Verdict CheckPair(double stamp, const cv::Mat& left, const cv::Mat& right, std::uint64_t arrival);

  // One image of one camera (0 left, 1 right) arrived at wall time `now` [s]; `pairs`: stereo
  // pairs synchronised so far (OnPair's count).
  std::vector<InputEvent> OnImage(int side, double now);
  // The synchroniser made a pair; counts it as received.
  std::vector<InputEvent> OnPair(double now);
  // Pairs the driver passed over or dropped (a tracker slower than the camera).
  void CountSkipped(std::uint64_t pairs);
  // A pair the driver refused before CheckPair (a message that is no image).
  void CountRefused();
  // Skipped pairs not reported yet, at most once a skip_report_period [s]; `last_frame_ms`: how
  // long the tracker took for its last pair, to say why.
  std::optional<InputEvent> SkipReport(double now, double last_frame_ms);
  bool HasUnreportedSkips() const;
  // When the next SkipReport can report [s, wall time].
  double NextSkipReport() const;

  InputCounts counts() const;

 private:
  mutable std::mutex mutex_;
  InputMonitorOptions options_;
  std::optional<cv::Size> image_size_;  // the calibration's; none yet: pairs are refused
  InputCounts counts_;
  std::optional<double> last_stamp_;
  std::uint64_t last_tracked_arrival_ = 0;
  // The last tracked pair's images (copies: a driver's images may be views of buffers that go
  // away), for telling a frozen camera.
  cv::Mat previous_left_, previous_right_;
  int frozen_frames_ = 0;
  // Per side: images counted, the wall time of the latest, and when its current stream began
  // (its previous image came more than dropout_seconds before).
  std::uint64_t images_[2] = {0, 0};
  std::optional<double> last_image_[2];
  double stream_start_[2] = {0, 0};
  bool dropout_reported_ = false;
  std::uint64_t skips_reported_ = 0;
  double last_skip_report_ = -1e300;
};

}  // namespace stereo_fabmap_slam::pipeline
