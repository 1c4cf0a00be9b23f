#pragma once

#include <cstddef>
#include <optional>
#include <vector>

#include <Eigen/Geometry>
#include <opencv2/core.hpp>

#include "stereo_fabmap_slam/evaluation/keypoint_transfer.h"
#include "stereo_fabmap_slam/features/features_options.h"
#include "stereo_fabmap_slam/geometry/stereo_camera.h"

namespace stereo_fabmap_slam::evaluation {

// A scene seen from two poses of a rectified stereo camera: the reference key point's stereo
// 3-D point, moved by the relative (ground-truth) pose and projected into the test left image.
class StereoPoseTransfer : public KeypointTransfer {
 public:
  // points[i]: reference key point i in the reference left camera frame, or nothing without
  // depth. T_test_reference maps reference camera coordinates to test camera coordinates.
  StereoPoseTransfer(const geometry::StereoCamera& camera,
                     std::vector<std::optional<Eigen::Vector3d>> points,
                     const Eigen::Isometry3d& T_test_reference);

  std::optional<cv::Point2f> Transfer(std::size_t index, const cv::Point2f& point) const override;

 private:
  geometry::StereoCamera camera_;
  std::vector<std::optional<Eigen::Vector3d>> points_;
  Eigen::Isometry3d T_test_reference_;
};

// Stereo 3-D points of left key points of a rectified pair, by the package's stereo matcher
// (patch mode) against the corners that `feature_options`' detector finds in the right image,
// so that each detector is judged with the depth it would get in the odometry.
std::vector<std::optional<Eigen::Vector3d>> TriangulateKeypoints(
    const cv::Mat& left, const cv::Mat& right, const std::vector<cv::KeyPoint>& keypoints,
    const features::FeatureOptions& feature_options,
    const features::StereoMatcherOptions& stereo_options, const geometry::StereoCamera& camera);

}  // namespace stereo_fabmap_slam::evaluation
