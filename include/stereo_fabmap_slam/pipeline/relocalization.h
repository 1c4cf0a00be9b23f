#pragma once

#include <functional>

#include <Eigen/Geometry>
#include <opencv2/core.hpp>

#include "stereo_fabmap_slam/features/stereo_features.h"
#include "stereo_fabmap_slam/geometry/stereo_camera.h"
#include "stereo_fabmap_slam/pipeline/loop_closing.h"
#include "stereo_fabmap_slam/relocalization/relocalizer.h"

namespace stereo_fabmap_slam::pipeline {

struct RelocalizationOutput {
  relocalization::Relocalization result;
  // The frame's camera in map (the keyframe's map pose times the relocalized relative pose);
  // meaningful on success.
  Eigen::Isometry3d T_map_camera = Eigen::Isometry3d::Identity();
  double ms = 0;  // place words, candidates, verification
  // Feature extraction when the frame was not tracked (StereoSlam::Relocalize); 0 otherwise.
  double extraction_ms = 0;
};

// The relocalization stage: one frame's stereo features and place descriptors against the map
// that loop closing keeps (keyframe database, FAB-MAP, pose graph).
class RelocalizationStage {
 public:
  using Clock = std::function<double()>;  // milliseconds, only read to fill the timing

  RelocalizationStage(const relocalization::RelocalizerOptions& options,
                      const geometry::StereoCamera& camera, int descriptor_norm,
                      double max_descriptor_distance, Clock clock)
      : relocalizer_(options, camera, descriptor_norm, max_descriptor_distance),
        clock_(std::move(clock)) {}

  // Among the keyframes `allowed` accepts. Throws std::invalid_argument for place descriptors
  // that do not fit the vocabulary.
  RelocalizationOutput Process(const features::StereoFeatures& frame,
                               const cv::Mat& place_descriptors, const LoopClosing& map,
                               const relocalization::Relocalizer::KeyframeFilter& allowed) const {
    RelocalizationOutput output;
    const double start = clock_();
    output.result = relocalizer_.Relocalize(frame, map.detector().Words(place_descriptors),
                                            map.detector(), allowed);
    if (output.result.success()) {
      output.T_map_camera =
          map.pose_graph().MapPose(output.result.keyframe_id) * output.result.T_keyframe_camera;
    }
    output.ms = clock_() - start;
    return output;
  }

  const relocalization::RelocalizerOptions& options() const { return relocalizer_.options(); }

 private:
  relocalization::Relocalizer relocalizer_;
  Clock clock_;
};

}  // namespace stereo_fabmap_slam::pipeline
