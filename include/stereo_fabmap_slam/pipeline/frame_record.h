#pragma once

#include <cstdint>
#include <optional>
#include <string>

#include <Eigen/Geometry>

#include "stereo_fabmap_slam/odometry/tracker.h"
#include "stereo_fabmap_slam/pipeline/place_stage.h"
#include "stereo_fabmap_slam/pipeline/stereo_front_end.h"

namespace stereo_fabmap_slam::pipeline {

// One processed frame, as a run's files report it.
struct FrameRecord {
  double timestamp = 0;
  odometry::TrackingState state = odometry::TrackingState::kLost;
  Eigen::Isometry3d T_world_camera = Eigen::Isometry3d::Identity();  // as tracked, in odom
  std::int64_t reference_keyframe = -1;
  Eigen::Isometry3d T_keyframe_camera = Eigen::Isometry3d::Identity();
  bool is_keyframe = false;
  int inliers = 0;   // map points tracked
  std::string note;  // the tracker's reason: why weak/lost, why a keyframe
  FrameTiming timing;
  // Whether the frame had a pose in the map when it was processed: false while tracking is lost
  // and while the odometry runs in a segment not (yet) found in the map (after a loss).
  bool on_map = true;
  // The relocalization attempt of the frame, if any: its outcome, in one line (timing.csv).
  std::optional<std::string> relocalization;
  // The attempt succeeded (recovering in mapping mode: and joined the segment to the map; a
  // first success awaiting confirmation is not counted).
  bool relocalized = false;
  // Localization mode: the frame's pose in the map when it was processed (map -> odom of the
  // latest relocalization times the odometry).
  std::optional<Eigen::Isometry3d> T_map_camera;
};

// timing.csv's account of a relocalization attempt: its outcome, keyframe and reason.
std::string DescribeRelocalization(const relocalization::Relocalization& relocalization);
// A relocalization's answer in its frame's record: its time and outcome, unless the answer was
// that a loop had joined the frame's segment meanwhile (nothing was tried).
void RecordRelocalization(const RelocalizationAnswer& answer, FrameRecord* record);

}  // namespace stereo_fabmap_slam::pipeline
