#include "stereo_fabmap_slam/evaluation/descriptor_case.h"

#include <memory>
#include <stdexcept>

#include "stereo_fabmap_slam/evaluation/homography_transfer.h"
#include "stereo_fabmap_slam/evaluation/stereo_pose_transfer.h"

namespace stereo_fabmap_slam::evaluation {

DescriptorCaseResult EvaluateDescriptorCase(const DescriptorCase& test_case,
                                            const features::FeatureOptions& pair,
                                            const DescriptorPrecisionRecallOptions& options,
                                            const std::function<double()>& now_ms) {
  if (!now_ms) throw std::invalid_argument("EvaluateDescriptorCase needs a clock");
  const FeaturePair made = MakeFeaturePair(pair);
  const double start = now_ms();
  const DescribedImage reference =
      DetectAndDescribe(test_case.reference, made, options.max_keypoints);
  const DescribedImage test = DetectAndDescribe(test_case.test, made, options.max_keypoints);
  const double described = now_ms();

  std::unique_ptr<KeypointTransfer> transfer;
  if (test_case.stereo) {
    const DescriptorCase::Stereo& stereo = *test_case.stereo;
    if (stereo.reference_right.size() != test_case.reference.size() ||
        stereo.camera.size != test_case.test.size()) {
      throw std::invalid_argument("case " + test_case.name +
                                  ": stereo images and camera differ in size");
    }
    transfer = std::make_unique<StereoPoseTransfer>(
        stereo.camera,
        TriangulateKeypoints(test_case.reference, stereo.reference_right, reference.keypoints, pair,
                             stereo.matcher, stereo.camera),
        stereo.T_test_reference);
  } else {
    transfer = std::make_unique<HomographyTransfer>(test_case.homography, test_case.test.size());
  }

  DescriptorCaseResult result;
  result.precision_recall = PrecisionRecall(reference, test, *transfer, options);
  result.milliseconds_per_image = (described - start) / 2;
  return result;
}

}  // namespace stereo_fabmap_slam::evaluation
