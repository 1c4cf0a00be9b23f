#include "stereo_fabmap_slam/place_recognition/image_describer.h"

#include <utility>

#include "stereo_fabmap_slam/features/anms.h"

namespace stereo_fabmap_slam::place_recognition {

ImageDescriber::ImageDescriber(const features::FeatureOptions& options)
    : ImageDescriber(options, features::CreateDescriptor(options)) {}

ImageDescriber::ImageDescriber(const features::FeatureOptions& options,
                               features::DescriptorKind descriptor)
    : options_((options.Validate(), options)),
      detector_(options, /*stereo_candidates=*/false),
      descriptor_(std::move(descriptor)) {}

cv::Mat ImageDescriber::Describe(const cv::Mat& image) {
  return Compute(image, detector_.Detect(image));
}

cv::Mat ImageDescriber::DescribeWithoutAdapting(const cv::Mat& image) const {
  return Compute(image, detector_.DetectRows(image, 0, image.rows));
}

cv::Mat ImageDescriber::Compute(const cv::Mat& image, std::vector<cv::KeyPoint> keypoints) const {
  keypoints = options_.anms
                  ? features::SelectWithAnms(std::move(keypoints), options_.max_features,
                                             image.size(), options_.anms_tolerance)
                  : features::SelectStrongest(std::move(keypoints), options_.max_features);
  cv::Mat descriptors;
  descriptor_.extractor->compute(image, keypoints, descriptors);
  return descriptors;
}

}  // namespace stereo_fabmap_slam::place_recognition
