#include "stereo_fabmap_slam/backend/window_covariance.h"

#include <cmath>
#include <stdexcept>

#include <Eigen/Cholesky>

namespace stereo_fabmap_slam::backend {

WindowCovariance::WindowCovariance(const geometry::StereoCamera& camera, double sigma,
                                   double huber_threshold)
    : camera_(camera), sigma_(sigma), huber_threshold_(huber_threshold) {}

int WindowCovariance::AddPose(const Eigen::Isometry3d& T_world_camera, bool free) {
  poses_.push_back(T_world_camera.inverse());
  free_index_.push_back(free ? free_count_++ : -1);
  return static_cast<int>(poses_.size()) - 1;
}

void WindowCovariance::AddPoint(const Eigen::Vector3d& point_world,
                                const std::vector<Observation>& observations) {
  if (reduced_.size() == 0) reduced_ = Eigen::MatrixXd::Zero(6 * free_count_, 6 * free_count_);
  // Per observation: its whitened Jacobians with respect to the pose (right perturbation) and
  // the point; the point's own 3x3 block is summed over all of them.
  struct Block {
    int free;
    Matrix36 pose;
    Eigen::Matrix3d point;
    int rows;
  };
  std::vector<Block> blocks;
  blocks.reserve(observations.size());
  Eigen::Matrix3d point_information = Eigen::Matrix3d::Zero();
  for (const Observation& o : observations) {
    const Eigen::Isometry3d& T_camera_world = poses_.at(static_cast<std::size_t>(o.pose));
    const Eigen::Vector3d p = T_camera_world * point_world;
    if (p.z() <= 0) continue;
    const int rows = o.u_right >= 0 ? 3 : 2;
    const Eigen::Vector3d predicted = camera_.Project(p);
    const Eigen::Vector3d measured(o.u, o.v, o.u_right);
    const double squared = (predicted - measured).head(rows).squaredNorm() / (sigma_ * sigma_);
    // The Huber loss's weight at the optimum: 1 inside the threshold, threshold / |r| beyond.
    const double weight = squared <= huber_threshold_ * huber_threshold_
                              ? 1.0
                              : huber_threshold_ / std::sqrt(squared);
    const Eigen::Matrix3d projection =
        geometry::StereoProjectionJacobian(camera_, p) * (std::sqrt(weight) / sigma_);
    Block block;
    block.free = free_index_[static_cast<std::size_t>(o.pose)];
    block.rows = rows;
    // The point in the perturbed camera T * Exp(delta) is Exp(-delta) * p.
    block.pose.leftCols<3>() = -projection;
    block.pose.rightCols<3>() = projection * geometry::Skew(p);
    block.point = projection * T_camera_world.linear();
    point_information += block.point.topRows(rows).transpose() * block.point.topRows(rows);
    blocks.push_back(block);
  }
  // A point that the observations do not pin down (one ray) informs no pose: left out, as the
  // bundle adjustment leaves out points seen once.
  const Eigen::LDLT<Eigen::Matrix3d> point_decomposition(point_information);
  const Eigen::Vector3d pivots = point_decomposition.vectorD().cwiseAbs();
  if (point_decomposition.info() != Eigen::Success || pivots.minCoeff() <= 1e-9 * pivots.maxCoeff())
    return;
  // H_cc += J_c^T J_c and the Schur complement's -H_cp H_pp^-1 H_pc, over the free poses.
  std::vector<Matrix36> pose_point(blocks.size());  // H_pc^T per block: J_p^T J_c (3x6)
  for (std::size_t i = 0; i < blocks.size(); ++i) {
    const Block& b = blocks[i];
    if (b.free < 0) continue;
    const auto pose = b.pose.topRows(b.rows);
    reduced_.block<6, 6>(6 * b.free, 6 * b.free) += pose.transpose() * pose;
    pose_point[i] = b.point.topRows(b.rows).transpose() * pose;
  }
  for (std::size_t i = 0; i < blocks.size(); ++i) {
    if (blocks[i].free < 0) continue;
    const Matrix36 solved = point_decomposition.solve(pose_point[i]);
    for (std::size_t j = 0; j < blocks.size(); ++j) {
      if (blocks[j].free < 0) continue;
      reduced_.block<6, 6>(6 * blocks[j].free, 6 * blocks[i].free) -=
          pose_point[j].transpose() * solved;
    }
  }
}

bool WindowCovariance::Compute() {
  if (free_count_ == 0) return false;
  if (reduced_.size() == 0) return false;
  const Eigen::LDLT<Eigen::MatrixXd> decomposition(0.5 * (reduced_ + reduced_.transpose()));
  const Eigen::VectorXd pivots = decomposition.vectorD();
  // Not positive definite, or a direction 1e-12 weaker than the strongest: a free pose the
  // points leave (nearly) unconstrained; its inverse would be noise.
  if (decomposition.info() != Eigen::Success || pivots.minCoeff() <= 1e-12 * pivots.maxCoeff())
    return false;
  covariance_ = decomposition.solve(Eigen::MatrixXd::Identity(6 * free_count_, 6 * free_count_));
  return true;
}

geometry::PoseCovariance WindowCovariance::RelativeCovariance(int a, int b) const {
  const int fa = free_index_.at(static_cast<std::size_t>(a));
  const int fb = free_index_.at(static_cast<std::size_t>(b));
  if ((fa < 0 && fb < 0) || covariance_.size() == 0) {
    throw std::logic_error("WindowCovariance::RelativeCovariance: no free pose, or not computed");
  }
  // T_a^-1 T_b perturbed: Exp(-delta_a) T_a^-1 T_b Exp(delta_b)
  //   = T_ab Exp(-Ad(T_ab^-1) delta_a) Exp(delta_b), so delta_ab = delta_b - Ad(T_ab^-1) delta_a.
  const Eigen::Isometry3d T_ab =
      poses_[static_cast<std::size_t>(a)] * poses_[static_cast<std::size_t>(b)].inverse();
  Eigen::Matrix<double, 6, 12> jacobian;
  jacobian.leftCols<6>() = -geometry::Adjoint(T_ab.inverse());
  jacobian.rightCols<6>().setIdentity();
  Eigen::Matrix<double, 12, 12> joint = Eigen::Matrix<double, 12, 12>::Zero();
  const int index[2] = {fa, fb};
  for (int i = 0; i < 2; ++i) {
    for (int j = 0; j < 2; ++j) {
      if (index[i] < 0 || index[j] < 0) continue;
      joint.block<6, 6>(6 * i, 6 * j) = covariance_.block<6, 6>(6 * index[i], 6 * index[j]);
    }
  }
  const geometry::PoseCovariance relative = jacobian * joint * jacobian.transpose();
  return 0.5 * (relative + relative.transpose());
}

}  // namespace stereo_fabmap_slam::backend
