#pragma once

#include <cstdint>
#include <functional>
#include <string>

#include "stereo_fabmap_slam/camera/camera_calibration.h"
#include "stereo_fabmap_slam/datasets/hall_scene.h"
#include "stereo_fabmap_slam/datasets/route.h"

namespace stereo_fabmap_slam::datasets {

struct SyntheticSequenceOptions {
  std::string route = "loop";  // loop, figure8, kidnap
  double seconds = 40.0;
  std::uint64_t seed = 1;         // the hall (photos, obstacles) and the image noise
  double noise_sigma = 2.0;       // [grey levels] per-pixel Gaussian noise
  bool distortion = true;         // EuRoC's radial-tangential lens distortion (else ideal pinhole)
  bool exposure_changes = false;  // slow, independent gain changes of the two cameras
  bool motion_blur = false;       // average over a 10 ms exposure
  std::string photo_folder = "/usr/share/doc/opencv-doc/examples/data";
  HallOptions hall;

  void Validate() const;  // throws std::invalid_argument
};

// Renders a stereo sequence of the synthetic hall into EuRoC's ASL layout: mav0/cam0 and cam1
// (data.csv, data/<stamp>.png, sensor.yaml), mav0/state_groundtruth_estimate0/data.csv (200 Hz
// body poses), mav0/synthetic.yaml (how it was made) and stereo_calibration.yaml (the rig for
// the nodelets, as config/euroc_stereo.yaml). The same options give the same bytes.
class SyntheticSequence {
 public:
  explicit SyntheticSequence(const SyntheticSequenceOptions& options);

  // `progress(frame, frames)` is called after each frame if given.
  void Write(const std::string& directory,
             const std::function<void(int, int)>& progress = nullptr) const;

  // The EuRoC-like stereo rig: 752 x 480 at 20 Hz, EuRoC's intrinsics (focal ~458 px) and, if
  // asked, its distortion; baseline 0.11 m; cameras looking along the body's x axis.
  static camera::StereoCalibration Rig(bool distortion);
  static constexpr std::int64_t kStartNs = 1'500'000'000'000'000'000;  // first image stamp
  static constexpr std::int64_t kFrameNs = 50'000'000;                 // 20 Hz

  int frame_count() const;

 private:
  SyntheticSequenceOptions options_;
  HallScene scene_;
  Route route_;
};

}  // namespace stereo_fabmap_slam::datasets
