// The pose covariance the odometry publishes: its prediction against the scatter of many noisy
// refinements (Monte Carlo), and its change of frame against sampled poses.
#include "stereo_fabmap_slam/geometry/pose_covariance.h"

#include <random>

#include <gtest/gtest.h>

#include "stereo_fabmap_slam/geometry/pose_refiner.h"

namespace stereo_fabmap_slam::test {
namespace {

const geometry::StereoCamera kCamera{cv::Size(752, 480), 435.0, 435.0, 367.0, 248.0, 0.11};

Eigen::Isometry3d Perturbation(const Eigen::Matrix<double, 6, 1>& delta) {
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.translation() = delta.head<3>();
  if (delta.tail<3>().norm() > 0) {
    T.linear() =
        Eigen::AngleAxisd(delta.tail<3>().norm(), delta.tail<3>().normalized()).toRotationMatrix();
  }
  return T;
}

// delta with estimate = truth * Perturbation(delta), to first order.
Eigen::Matrix<double, 6, 1> RightError(const Eigen::Isometry3d& truth,
                                       const Eigen::Isometry3d& estimate) {
  const Eigen::Isometry3d difference = truth.inverse() * estimate;
  const Eigen::AngleAxisd angle_axis(difference.rotation());
  Eigen::Matrix<double, 6, 1> delta;
  delta << difference.translation(), angle_axis.angle() * angle_axis.axis();
  return delta;
}

Eigen::Matrix<double, 6, 6> EmpiricalCovariance(
    const std::vector<Eigen::Matrix<double, 6, 1>>& samples) {
  Eigen::Matrix<double, 6, 1> mean = Eigen::Matrix<double, 6, 1>::Zero();
  for (const auto& sample : samples) mean += sample;
  mean /= static_cast<double>(samples.size());
  Eigen::Matrix<double, 6, 6> covariance = Eigen::Matrix<double, 6, 6>::Zero();
  for (const auto& sample : samples) covariance += (sample - mean) * (sample - mean).transpose();
  return covariance / static_cast<double>(samples.size() - 1);
}

// 400 refinements of one pose from 60 points 2-10 m away seen with 1 px Gaussian noise (a third
// of them without a stereo match): the predicted standard deviations match the scatter. With 400
// samples a variance is known to sqrt(2/400) = 7 %, a standard deviation to 3.5 %; 15 % is
// four of those.
TEST(PoseCovariance, PredictsTheScatterOfNoisyRefinements) {
  std::mt19937_64 random(7);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  std::normal_distribution<double> noise(0.0, 1.0);
  Eigen::Isometry3d T_world_camera = Eigen::Isometry3d::Identity();
  T_world_camera.linear() =
      Eigen::AngleAxisd(0.3, Eigen::Vector3d(0.1, 1.0, 0.2).normalized()).toRotationMatrix();
  T_world_camera.translation() = Eigen::Vector3d(1.0, 0.2, -0.5);
  std::vector<Eigen::Vector3d> camera_points;
  std::vector<bool> stereo;
  for (int i = 0; i < 60; ++i) {
    const double z = 2.0 + 8.0 * unit(random);
    camera_points.emplace_back((unit(random) * 700 - 340) * z / 435,
                               (unit(random) * 440 - 228) * z / 435, z);
    stereo.push_back(i % 3 != 0);
  }
  std::vector<geometry::ObservedPoint> observed;
  for (std::size_t i = 0; i < camera_points.size(); ++i) {
    observed.push_back({camera_points[i], stereo[i]});
  }
  const geometry::PoseCovariance predicted = geometry::StereoPoseCovariance(kCamera, observed, 1.0);

  geometry::PoseRefinementOptions options;
  options.sigma = 1.0;
  std::vector<Eigen::Matrix<double, 6, 1>> errors;
  geometry::PoseCovariance reported = geometry::PoseCovariance::Zero();
  for (int trial = 0; trial < 400; ++trial) {
    std::vector<geometry::PoseObservation> observations;
    for (std::size_t i = 0; i < camera_points.size(); ++i) {
      const Eigen::Vector3d pixels = kCamera.Project(camera_points[i]);
      observations.push_back({T_world_camera * camera_points[i], pixels.x() + noise(random),
                              pixels.y() + noise(random),
                              stereo[i] ? pixels.z() + noise(random) : -1.0});
    }
    const geometry::PoseRefinement refined =
        geometry::RefinePose(observations, kCamera, T_world_camera.inverse(), options);
    errors.push_back(RightError(T_world_camera, refined.T_camera_world.inverse()));
    reported += refined.covariance / 400.0;
  }
  const Eigen::Matrix<double, 6, 6> measured = EmpiricalCovariance(errors);
  for (int k = 0; k < 6; ++k) {
    EXPECT_NEAR(std::sqrt(measured(k, k)), std::sqrt(predicted(k, k)),
                0.15 * std::sqrt(predicted(k, k)))
        << "axis " << k;
  }
  // The refinement reports the same covariance from its own inliers: the chi-square test at 95 %
  // leaves out about 5 % of the points, so its variances are that much larger on average.
  for (int k = 0; k < 6; ++k) {
    EXPECT_NEAR(reported(k, k), 1.05 * predicted(k, k), 0.05 * predicted(k, k)) << "axis " << k;
  }
  // Depth is the weakest direction of a forward-looking camera: the z translation varies most.
  EXPECT_GT(predicted(2, 2), predicted(0, 0));
}

// Samples of T * Exp(delta) carried by a fixed B scatter around T * B as the moved covariance
// says. Small deltas keep the first-order model exact to well within the 5 % sampling margin
// (10,000 samples: a variance to 1.4 %).
TEST(PoseCovariance, MovesToAnotherFrameLikeSampledPoses) {
  std::mt19937_64 random(11);
  std::normal_distribution<double> normal(0.0, 1.0);
  Eigen::Matrix<double, 6, 6> square_root = Eigen::Matrix<double, 6, 6>::Zero();
  for (int r = 0; r < 6; ++r) {
    for (int c = 0; c <= r; ++c) square_root(r, c) = 1e-3 * (r == c ? 2.0 : 0.5);
  }
  const geometry::PoseCovariance covariance = square_root * square_root.transpose();
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.translation() = Eigen::Vector3d(3, -1, 2);
  Eigen::Isometry3d B = Eigen::Isometry3d::Identity();
  B.linear() = Eigen::AngleAxisd(1.2, Eigen::Vector3d(1, 2, 3).normalized()).toRotationMatrix();
  B.translation() = Eigen::Vector3d(0.5, -2.0, 1.0);  // a long lever arm: rotation moves it
  std::vector<Eigen::Matrix<double, 6, 1>> errors;
  for (int i = 0; i < 10000; ++i) {
    Eigen::Matrix<double, 6, 1> z;
    for (int k = 0; k < 6; ++k) z(k) = normal(random);
    errors.push_back(RightError(T * B, T * Perturbation(square_root * z) * B));
  }
  const Eigen::Matrix<double, 6, 6> measured = EmpiricalCovariance(errors);
  const geometry::PoseCovariance moved = geometry::MoveCovarianceToFrame(covariance, B);
  for (int r = 0; r < 6; ++r) {
    for (int c = 0; c < 6; ++c) {
      EXPECT_NEAR(measured(r, c), moved(r, c), 0.05 * std::sqrt(moved(r, r) * moved(c, c)))
          << r << "," << c;
    }
  }
  // Turning the axes by 90 degrees about z: what was along x is along y.
  geometry::PoseCovariance uneven = geometry::PoseCovariance::Zero();
  uneven.diagonal() << 1, 4, 9, 16, 25, 36;
  const geometry::PoseCovariance rotated = geometry::RotateCovariance(
      uneven, Eigen::AngleAxisd(M_PI / 2, Eigen::Vector3d::UnitZ()).toRotationMatrix());
  EXPECT_NEAR(rotated(0, 0), 4, 1e-12);
  EXPECT_NEAR(rotated(1, 1), 1, 1e-12);
  EXPECT_NEAR(rotated(2, 2), 9, 1e-12);
  EXPECT_NEAR(rotated(3, 3), 25, 1e-12);
  EXPECT_NEAR(rotated(4, 4), 16, 1e-12);
}

TEST(PoseCovariance, TooFewPointsAreUnknownNotZero) {
  const geometry::PoseCovariance covariance = geometry::StereoPoseCovariance(
      kCamera, {{Eigen::Vector3d(0, 0, 5), true}, {Eigen::Vector3d(1, 0, 5), true}}, 1.0);
  EXPECT_GE(covariance.diagonal().minCoeff(), 1e5);
}

}  // namespace
}  // namespace stereo_fabmap_slam::test
