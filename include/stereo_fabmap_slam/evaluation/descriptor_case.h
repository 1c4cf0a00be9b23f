#pragma once

#include <functional>
#include <optional>
#include <string>

#include <Eigen/Geometry>
#include <opencv2/core.hpp>

#include "stereo_fabmap_slam/evaluation/descriptor_precision_recall.h"
#include "stereo_fabmap_slam/features/features_options.h"
#include "stereo_fabmap_slam/geometry/stereo_camera.h"

namespace stereo_fabmap_slam::evaluation {

// A reference and a test image with the geometry between them: a homography (the identity for
// the same view under other illumination), or a rectified stereo camera whose reference depth
// comes from its right image and whose motion is known from ground truth.
struct DescriptorCase {
  struct Stereo {
    cv::Mat reference_right;  // rectified right image beside `reference`
    geometry::StereoCamera camera;
    Eigen::Isometry3d T_test_reference = Eigen::Isometry3d::Identity();
    features::StereoMatcherOptions matcher;
  };

  std::string name;
  cv::Mat reference, test;  // 8-bit grey; the rectified left images in a stereo case
  cv::Matx33d homography = cv::Matx33d::eye();  // used when stereo is empty
  std::optional<Stereo> stereo;
};

struct DescriptorCaseResult {
  DescriptorPrecisionRecall precision_recall;
  double milliseconds_per_image = 0;  // detection and description, the mean of the two images
};

// Describes both images with the detector/descriptor `pair` and measures precision-recall.
// `now_ms` is the clock that times detection and description (the library reads none itself).
DescriptorCaseResult EvaluateDescriptorCase(const DescriptorCase& test_case,
                                            const features::FeatureOptions& pair,
                                            const DescriptorPrecisionRecallOptions& options,
                                            const std::function<double()>& now_ms);

}  // namespace stereo_fabmap_slam::evaluation
