#pragma once

#include <ostream>
#include <string>

#include "stereo_fabmap_slam/backend/backend_options.h"
#include "stereo_fabmap_slam/camera/camera_options.h"
#include "stereo_fabmap_slam/camera/stereo_rectifier.h"
#include "stereo_fabmap_slam/dense/dense_options.h"
#include "stereo_fabmap_slam/pipeline/stereo_front_end.h"
#include "stereo_fabmap_slam/pipeline/stereo_slam.h"
#include "stereo_fabmap_slam/place_recognition/place_recognition_options.h"
#include "stereo_fabmap_slam/relocalization/relocalization_options.h"

namespace stereo_fabmap_slam::tools {

// What the offline tools read from config/euroc.yaml (and its presets): every section of the
// file, each into its module's Options. The nodelets read the same sections, each its own.
struct SlamConfiguration {
  camera::RectificationOptions rectification;
  pipeline::FrontEndOptions front_end;
  backend::BundleAdjustmentOptions bundle_adjustment;
  place_recognition::LoopDetectorOptions loop_detection;
  backend::PoseGraphOptions pose_graph;
  backend::GlobalRefinementOptions global_refinement;
  relocalization::RelocalizerOptions relocalization;
  dense::StereoDepthOptions dense_depth;
  dense::FusionOptions dense_fusion;
  dense::DenseMappingOptions dense_mapping;

  template <typename Visit>
  void ForEachModule(Visit visit) {
    visit(rectification);
    front_end.ForEachModule(visit);
    visit(bundle_adjustment);
    visit(loop_detection);
    visit(pose_graph);
    visit(global_refinement);
    visit(relocalization);
    visit(dense_depth);
    visit(dense_fusion);
    visit(dense_mapping);
  }

  // Reads and validates every section; unknown sections and keys, and bad values, throw
  // io::InputError naming the file (and line).
  static SlamConfiguration Load(const std::string& path);
  void Print(std::ostream& out) const;

  // Place recognition's options (a fabmap.yaml), and the front end told to make the place
  // descriptors they describe: what loop closing and relocalization need from every keyframe.
  place_recognition::PlaceRecognitionOptions LoadPlaceRecognition(const std::string& path);
  // Loop closing and relocalization on in `slam` (before its first frame), with these options
  // and FAB-MAP's files as `place` names them.
  void EnableLoopClosing(const place_recognition::PlaceRecognitionOptions& place,
                         const camera::StereoRectifier& rectifier,
                         pipeline::StereoSlam* slam) const;
};

}  // namespace stereo_fabmap_slam::tools
