#pragma once

#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "stereo_fabmap_slam/geometry/pose_covariance.h"
#include "stereo_fabmap_slam/geometry/stereo_camera.h"

namespace stereo_fabmap_slam::backend {

// The Gauss-Newton covariance of a bundle adjustment window's free camera poses at its optimum,
// with the points marginalised out (the reduced camera system, inverted). Residuals as the
// windowed bundle adjustment has them: stereo (u_left, v, u_right) or mono (u_left, v)
// reprojections at `sigma` pixels, each reweighted by its Huber loss at `huber_threshold`
// standard deviations (iteratively reweighted least squares' weight at the optimum). Fixed
// poses are the gauge: they enter through the points they see but carry no uncertainty.
// Perturbations are on the right of T_world_camera, ordered (translation, rotation), which is
// the pose graph's residual order for a relative pose (geometry::RelativePoseError).
class WindowCovariance {
 public:
  struct Observation {
    int pose;              // index returned by AddPose
    double u, v, u_right;  // u_right < 0: mono
  };

  WindowCovariance(const geometry::StereoCamera& camera, double sigma, double huber_threshold);

  // Returns the pose's index for observations.
  int AddPose(const Eigen::Isometry3d& T_world_camera, bool free);
  // A point at its optimum and its observations (poses added before).
  void AddPoint(const Eigen::Vector3d& point_world, const std::vector<Observation>& observations);
  // Inverts the reduced camera system; false if it is not positive definite (a free pose that
  // the points do not pin down).
  bool Compute();
  // After Compute(): the covariance of T_a^-1 * T_b (perturbed on its right) for two added poses
  // of which at least one is free.
  geometry::PoseCovariance RelativeCovariance(int a, int b) const;

 private:
  using Matrix36 = Eigen::Matrix<double, 3, 6>;

  geometry::StereoCamera camera_;
  double sigma_, huber_threshold_;
  std::vector<Eigen::Isometry3d> poses_;  // T_camera_world, inverted once for every observation
  std::vector<int> free_index_;  // per pose: its block in the reduced system, or -1 if fixed
  int free_count_ = 0;
  Eigen::MatrixXd reduced_;     // 6F x 6F: H_cc - H_cp H_pp^-1 H_pc
  Eigen::MatrixXd covariance_;  // its inverse
};

}  // namespace stereo_fabmap_slam::backend
