#pragma once

#include <cstdint>
#include <functional>
#include <string>

#include "stereo_fabmap_slam/camera/camera_calibration.h"
#include "stereo_fabmap_slam/datasets/hall_scene.h"
#include "stereo_fabmap_slam/datasets/office_floor.h"
#include "stereo_fabmap_slam/datasets/route.h"

namespace stereo_fabmap_slam::datasets {

struct SyntheticSequenceOptions {
  std::string scene = "hall";  // hall (photographs on the walls) or office (OfficeFloor)
  std::string route = "loop";  // loop, figure8, kidnap
  double seconds = 40.0;
  std::uint64_t seed = 1;         // the hall (photos, obstacles) and the image noise
  double noise_sigma = 2.0;       // [grey levels] per-pixel Gaussian noise
  bool distortion = true;         // EuRoC's radial-tangential lens distortion (else ideal pinhole)
  bool exposure_changes = false;  // slow, independent gain changes of the two cameras
  bool motion_blur = false;       // average over a 10 ms exposure
  // Each camera's gain follows the brightness of what it sees (0.3 s time constant), as a real
  // camera's auto exposure does when a corridor of lights or a dark door fills the view. On by
  // default in the office (see ForScene).
  bool auto_exposure = false;
  cv::Size resolution{752, 480};  // EuRoC's; the same field of view at any other size
  std::string photo_folder = "/usr/share/doc/opencv-doc/examples/data";  // the hall's
  HallOptions hall;
  OfficeOptions office;

  // The defaults of a scene: the office turns auto exposure on.
  static SyntheticSequenceOptions ForScene(const std::string& scene);

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
  // asked, its distortion; baseline 0.11 m; cameras looking along the body's x axis. Another
  // `resolution` scales the focal lengths with the width (the same horizontal field of view,
  // square pixels) and keeps the principal point's offset from the centre in proportion.
  static camera::StereoCalibration Rig(bool distortion, cv::Size resolution = {752, 480});
  static constexpr std::int64_t kStartNs = 1'500'000'000'000'000'000;  // first image stamp
  static constexpr std::int64_t kFrameNs = 50'000'000;                 // 20 Hz

  int frame_count() const;
  // The geometry of the world a sequence written by Write() shows, from its
  // mav0/synthetic.yaml (scene and seed; the hall's photographs as by default, which only
  // texture it). Throws std::runtime_error if the file is missing or says neither.
  static HallScene SceneOf(const std::string& directory);

 private:
  SyntheticSequenceOptions options_;
  HallScene scene_;
  Route route_;
};

}  // namespace stereo_fabmap_slam::datasets
