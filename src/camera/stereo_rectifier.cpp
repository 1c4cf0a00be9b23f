#include "stereo_fabmap_slam/camera/stereo_rectifier.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

#include <opencv2/calib3d.hpp>
#include <opencv2/imgproc.hpp>

namespace stereo_fabmap_slam::camera {
namespace {

Eigen::Matrix3d ToEigen(const cv::Matx33d& m) {
  Eigen::Matrix3d e;
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 3; ++c) e(r, c) = m(r, c);
  }
  return e;
}

void CheckImage(const cv::Mat& image, const cv::Size& size, const char* side) {
  if (image.empty()) throw std::invalid_argument(std::string(side) + " image is empty");
  if (image.type() != CV_8UC1) {
    throw std::invalid_argument(std::string(side) + " image must be mono8");
  }
  if (image.size() != size) {
    throw std::invalid_argument(std::string(side) + " image is " + std::to_string(image.cols) +
                                "x" + std::to_string(image.rows) + ", calibration expects " +
                                std::to_string(size.width) + "x" + std::to_string(size.height));
  }
}

}  // namespace

StereoRectifier StereoRectifier::FromCalibration(const StereoCalibration& calibration,
                                                 const RectificationOptions& options) {
  calibration.Validate();
  options.Validate();
  const Eigen::Isometry3d T_right_left = calibration.T_right_left();
  cv::Matx33d rotation;
  cv::Vec3d translation;
  for (int r = 0; r < 3; ++r) {
    translation[r] = T_right_left.translation()[r];
    for (int c = 0; c < 3; ++c) rotation(r, c) = T_right_left.linear()(r, c);
  }
  RectificationParameters left{calibration.left.resolution,
                               calibration.left.CameraMatrix(),
                               calibration.left.distortion,
                               {},
                               {}};
  RectificationParameters right{calibration.right.resolution,
                                calibration.right.CameraMatrix(),
                                calibration.right.distortion,
                                {},
                                {}};
  cv::Mat Q;
  cv::stereoRectify(left.K, left.D, right.K, right.D, left.size, rotation, translation, left.R,
                    right.R, left.P, right.P, Q, cv::CALIB_ZERO_DISPARITY, options.alpha,
                    left.size);
  return FromParameters(left, right, calibration.left.T_body_camera);
}

StereoRectifier StereoRectifier::FromParameters(const RectificationParameters& left,
                                                const RectificationParameters& right,
                                                const Eigen::Isometry3d& T_body_left_raw) {
  if (left.size != right.size || left.size.area() <= 0) {
    throw std::invalid_argument("left and right images must have the same, non-zero size");
  }
  const cv::Matx34d& P1 = left.P;
  const cv::Matx34d& P2 = right.P;
  const double tolerance = 1e-6 * std::max(1.0, P1(0, 0));
  if (!(P1(0, 0) > 0) || !(P1(1, 1) > 0)) {
    throw std::invalid_argument("rectified focal lengths must be positive");
  }
  if (std::abs(P1(0, 0) - P2(0, 0)) > tolerance || std::abs(P1(1, 1) - P2(1, 1)) > tolerance ||
      std::abs(P1(0, 2) - P2(0, 2)) > tolerance || std::abs(P1(1, 2) - P2(1, 2)) > tolerance) {
    throw std::invalid_argument("left and right projections differ: not a rectified pair");
  }
  if (std::abs(P2(1, 3)) > tolerance || !(P2(0, 3) < 0)) {
    throw std::invalid_argument(
        "right projection must place the right camera to the right of the left one "
        "(horizontal stereo, P_right[0][3] = -fx * baseline < 0)");
  }
  StereoRectifier rectifier;
  rectifier.left_ = left;
  rectifier.right_ = right;
  rectifier.camera_.size = left.size;
  rectifier.camera_.fx = P1(0, 0);
  rectifier.camera_.fy = P1(1, 1);
  rectifier.camera_.cx = P1(0, 2);
  rectifier.camera_.cy = P1(1, 2);
  rectifier.camera_.baseline = -P2(0, 3) / P2(0, 0);
  Eigen::Isometry3d T_raw_rectified = Eigen::Isometry3d::Identity();
  T_raw_rectified.linear() = ToEigen(left.R).transpose();
  rectifier.T_body_rectified_left_ = T_body_left_raw * T_raw_rectified;

  const cv::Matx33d K_rectified = rectifier.camera_.CameraMatrix();
  cv::initUndistortRectifyMap(left.K, left.D, left.R, K_rectified, left.size, CV_16SC2,
                              rectifier.left_map1_, rectifier.left_map2_);
  cv::initUndistortRectifyMap(right.K, right.D, right.R, K_rectified, right.size, CV_16SC2,
                              rectifier.right_map1_, rectifier.right_map2_);
  return rectifier;
}

void StereoRectifier::Rectify(const cv::Mat& left_raw, const cv::Mat& right_raw, cv::Mat* left,
                              cv::Mat* right, concurrency::HelperThread* helper) const {
  CheckImage(left_raw, camera_.size, "left");
  CheckImage(right_raw, camera_.size, "right");
  if (helper == nullptr) {
    cv::remap(left_raw, *left, left_map1_, left_map2_, cv::INTER_LINEAR);
    cv::remap(right_raw, *right, right_map1_, right_map2_, cv::INTER_LINEAR);
    return;
  }
  // Bands of 48 rows: small enough for the two threads to end together (a band is about 5 % of
  // the pair's work), and under the 65,536 pixels at which cv::remap would split a band over
  // OpenCV's own threads as well. Each output pixel depends on its map entry alone, so the bands
  // give the whole image's result.
  constexpr int kBandRows = 48;
  left->create(camera_.size, CV_8UC1);
  right->create(camera_.size, CV_8UC1);
  const int bands = (camera_.size.height + kBandRows - 1) / kBandRows;
  helper->ForEachPiece(2 * bands, [&](int piece) {
    const bool is_left = piece < bands;
    const int top = (piece % bands) * kBandRows;
    const cv::Range rows(top, std::min(top + kBandRows, camera_.size.height));
    cv::Mat band = (is_left ? *left : *right).rowRange(rows);
    const cv::Mat& map1 = is_left ? left_map1_ : right_map1_;
    const cv::Mat& map2 = is_left ? left_map2_ : right_map2_;
    cv::remap(is_left ? left_raw : right_raw, band, map1.rowRange(rows), map2.rowRange(rows),
              cv::INTER_LINEAR);
  });
}

}  // namespace stereo_fabmap_slam::camera
