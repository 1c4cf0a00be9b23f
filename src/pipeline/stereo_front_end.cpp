#include "stereo_fabmap_slam/pipeline/stereo_front_end.h"

namespace stereo_fabmap_slam::pipeline {

StereoFrontEnd::StereoFrontEnd(const FrontEndOptions& options, camera::StereoRectifier rectifier,
                               Clock clock)
    : rectifier_(std::move(rectifier)),
      clock_(std::move(clock)),
      helper_(options.features.parallel || options.tracker.parallel
                  ? std::make_unique<concurrency::HelperThread>()
                  : nullptr),
      rectification_helper_(options.features.parallel ? helper_.get() : nullptr),
      extractor_(options.features, options.stereo, rectifier_.camera(), helper_.get()),
      tracker_(options.tracker, options.keyframes, rectifier_.camera(),
               extractor_.descriptor_norm(), extractor_.max_match_distance(), helper_.get()) {
  if (options.place_features) {
    // The odometry's descriptor instance when the places use the same descriptor and it can be
    // shared (BRISK: one 47 MB table instead of two).
    const features::DescriptorKind& odometry = extractor_.descriptor();
    place_describer_ =
        options.place_features->descriptor == options.features.descriptor && odometry.shareable
            ? std::make_unique<place_recognition::ImageDescriber>(*options.place_features, odometry)
            : std::make_unique<place_recognition::ImageDescriber>(*options.place_features);
  }
}

FrontEndOutput StereoFrontEnd::Process(double timestamp, const cv::Mat& left_raw,
                                       const cv::Mat& right_raw, int frames_skipped) {
  FrontEndOutput output;
  FrameTiming& timing = output.timing;
  double start = clock_();
  const auto lap = [&](double* stage) {
    const double now = clock_();
    *stage = now - start;
    start = now;
  };
  cv::Mat left, right;
  rectifier_.Rectify(left_raw, right_raw, &left, &right, rectification_helper_);
  lap(&timing.rectification_ms);
  features::StereoFeatureExtractor::Detected detected = extractor_.Detect(left, right);
  lap(&timing.detection_ms);
  features::StereoFeatureExtractor::Described described =
      extractor_.Describe(left, right, std::move(detected));
  lap(&timing.description_ms);
  features::StereoFeatures features = extractor_.Match(left, right, std::move(described));
  lap(&timing.stereo_ms);
  // Kept only where a relocalization may need them after tracking consumed them (place
  // recognition on): a copy per frame is not free.
  if (place_describer_) output.features = features;
  output.tracking = tracker_.Track(timestamp, std::move(features), frames_skipped);
  lap(&timing.tracking_ms);
  last_left_ = left;
  if (output.tracking.keyframe && place_describer_) {
    output.tracking.keyframe->place_descriptors = place_describer_->Describe(left);
    lap(&timing.place_description_ms);
  }
  return output;
}

cv::Mat StereoFrontEnd::DescribeLastFrame() const {
  if (!place_describer_ || last_left_.empty()) return cv::Mat();
  return place_describer_->DescribeWithoutAdapting(last_left_);
}

features::StereoFeatures StereoFrontEnd::Extract(const cv::Mat& left_raw, const cv::Mat& right_raw,
                                                 cv::Mat* place_descriptors) const {
  cv::Mat left, right;
  rectifier_.Rectify(left_raw, right_raw, &left, &right);
  features::StereoFeatureExtractor::Detected detected =
      extractor_.DetectWithoutAdapting(left, right);
  features::StereoFeatureExtractor::Described described =
      extractor_.Describe(left, right, std::move(detected));
  if (place_descriptors != nullptr) {
    *place_descriptors =
        place_describer_ ? place_describer_->DescribeWithoutAdapting(left) : cv::Mat();
  }
  return extractor_.Match(left, right, std::move(described));
}

}  // namespace stereo_fabmap_slam::pipeline
