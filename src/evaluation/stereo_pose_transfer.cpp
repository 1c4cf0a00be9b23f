#include "stereo_fabmap_slam/evaluation/stereo_pose_transfer.h"

#include <utility>

#include "stereo_fabmap_slam/features/feature_factory.h"
#include "stereo_fabmap_slam/features/stereo_matcher.h"

namespace stereo_fabmap_slam::evaluation {

StereoPoseTransfer::StereoPoseTransfer(const geometry::StereoCamera& camera,
                                       std::vector<std::optional<Eigen::Vector3d>> points,
                                       const Eigen::Isometry3d& T_test_reference)
    : camera_(camera), points_(std::move(points)), T_test_reference_(T_test_reference) {}

std::optional<cv::Point2f> StereoPoseTransfer::Transfer(std::size_t index,
                                                        const cv::Point2f& /*point*/) const {
  if (index >= points_.size() || !points_[index]) return std::nullopt;
  const Eigen::Vector3d in_test = T_test_reference_ * *points_[index];
  if (in_test.z() <= 1e-6) return std::nullopt;
  const Eigen::Vector3d projected = camera_.Project(in_test);
  const double u = projected.x(), v = projected.y();
  if (!(u >= 0 && v >= 0 && u < camera_.size.width && v < camera_.size.height)) {
    return std::nullopt;
  }
  return cv::Point2f(static_cast<float>(u), static_cast<float>(v));
}

std::vector<std::optional<Eigen::Vector3d>> TriangulateKeypoints(
    const cv::Mat& left, const cv::Mat& right, const std::vector<cv::KeyPoint>& keypoints,
    const features::FeatureOptions& feature_options,
    const features::StereoMatcherOptions& stereo_options, const geometry::StereoCamera& camera) {
  // Patch mode compares image patches, so the right corners need no descriptors.
  features::StereoMatcherOptions patch_options = stereo_options;
  patch_options.mode = features::StereoMatchMode::kPatch;
  std::vector<cv::KeyPoint> right_keypoints;
  features::CreateDetector(feature_options)->detect(right, right_keypoints);
  const features::StereoMatcher matcher(patch_options, camera, cv::NORM_HAMMING,
                                        /*max_descriptor_distance=*/0);
  const std::vector<float> u_right =
      matcher.Match(left, keypoints, cv::Mat(), right, right_keypoints, cv::Mat());
  std::vector<std::optional<Eigen::Vector3d>> points(keypoints.size());
  for (std::size_t i = 0; i < keypoints.size(); ++i) {
    if (u_right[i] < 0) continue;
    const cv::Point2f& p = keypoints[i].pt;
    points[i] = camera.Triangulate(p.x, p.y, p.x - u_right[i]);
  }
  return points;
}

}  // namespace stereo_fabmap_slam::evaluation
