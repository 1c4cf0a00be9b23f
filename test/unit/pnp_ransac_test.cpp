#include "stereo_fabmap_slam/geometry/pnp_ransac.h"

#include <random>

#include <gtest/gtest.h>

namespace stereo_fabmap_slam::test {
namespace {

using geometry::PnpCorrespondence;
using geometry::PnpKernel;

struct Scene {
  std::vector<PnpCorrespondence> correspondences;
  std::vector<bool> is_inlier;
  Eigen::Isometry3d T_camera_world;
};

const geometry::StereoCamera kCamera{cv::Size(752, 480), 435.0, 435.0, 367.0, 248.0, 0.11};

// 300 points 2-12 m in front of a known camera, seen with 0.5 px noise; 30 % of the
// correspondences replaced by random pixels (and random stereo points).
Scene MakeScene(std::uint64_t seed) {
  std::mt19937_64 random(seed);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  std::normal_distribution<double> noise(0.0, 0.5);
  Scene scene;
  scene.T_camera_world = Eigen::Isometry3d::Identity();
  scene.T_camera_world.linear() =
      Eigen::AngleAxisd(0.4, Eigen::Vector3d(0.2, 1.0, -0.3).normalized()).toRotationMatrix();
  scene.T_camera_world.translation() = Eigen::Vector3d(0.5, -0.3, 1.2);
  const Eigen::Isometry3d T_world_camera = scene.T_camera_world.inverse();
  for (int i = 0; i < 300; ++i) {
    const double z = 2.0 + 10.0 * unit(random);
    const Eigen::Vector3d camera_point((unit(random) * 752 - 367) * z / 435,
                                       (unit(random) * 480 - 248) * z / 435, z);
    PnpCorrespondence c;
    c.world = T_world_camera * camera_point;
    const Eigen::Vector3d pixels = kCamera.Project(camera_point);
    c.pixel = Eigen::Vector2d(pixels.x() + noise(random), pixels.y() + noise(random));
    c.has_depth = true;
    // The stereo point carries the same pixel noise through the triangulation.
    c.camera_point =
        kCamera.Triangulate(c.pixel.x(), c.pixel.y(), pixels.x() - pixels.z() + noise(random));
    const bool outlier = unit(random) < 0.3;
    if (outlier) {
      c.pixel = Eigen::Vector2d(unit(random) * 752, unit(random) * 480);
      c.camera_point =
          Eigen::Vector3d(unit(random) * 4 - 2, unit(random) * 4 - 2, 2 + 10 * unit(random));
    }
    scene.correspondences.push_back(c);
    scene.is_inlier.push_back(!outlier);
  }
  return scene;
}

class PnpKernelTest : public ::testing::TestWithParam<std::string> {};

TEST_P(PnpKernelTest, RecoversAKnownPoseWith30PercentOutliers) {
  const Scene scene = MakeScene(7);
  geometry::PnpRansacOptions options;
  options.kernel = *geometry::ParsePnpKernel(GetParam());
  options.max_iterations = 200;
  // The iterative kernel starts from a guess: 10 cm and 3 degrees off.
  Eigen::Isometry3d guess = scene.T_camera_world;
  guess.translation() += Eigen::Vector3d(0.1, 0.0, 0.0);
  guess.linear() =
      guess.linear() * Eigen::AngleAxisd(0.05, Eigen::Vector3d::UnitY()).toRotationMatrix();
  const geometry::PnpResult result =
      geometry::SolvePnpRansac(scene.correspondences, kCamera, options, guess);
  ASSERT_TRUE(result.success);
  const Eigen::Isometry3d error = result.T_camera_world * scene.T_camera_world.inverse();
  // 0.5 px noise over ~200 inliers at 2-12 m pins the pose to millimetres and hundredths of a
  // degree; the limits leave a factor of ~5 for the minimal kernels' re-fit.
  EXPECT_LT(Eigen::AngleAxisd(error.linear()).angle() * 180 / M_PI, 0.2);
  EXPECT_LT(
      (result.T_camera_world.inverse().translation() - scene.T_camera_world.inverse().translation())
          .norm(),
      0.03);
  int true_inliers = 0, false_inliers = 0, all_inliers = 0;
  for (const int i : result.inliers) (scene.is_inlier[i] ? true_inliers : false_inliers)++;
  for (const bool inlier : scene.is_inlier) all_inliers += inlier ? 1 : 0;
  EXPECT_GE(true_inliers, 0.95 * all_inliers);
  // A random pixel falls within 2 px of the right place by chance very rarely.
  EXPECT_LE(false_inliers, 3);
}

INSTANTIATE_TEST_SUITE_P(AllKernels, PnpKernelTest,
                         ::testing::Values("ITERATIVE", "EPNP", "AP3P", "P3P", "SQPNP", "UMEYAMA"));

// A plane (a wall, a stack of pallets seen face on) is where OpenCV's own re-fit of its
// consensus goes wrong: after AP3P and P3P it re-fits with EPnP, which is ill-conditioned on
// planar points, and in about half the seeds below its pose kept under 70 % of its consensus
// within the threshold (191 of 240 once fell to 11). SolvePnpRansac re-fits by reprojection
// error; every seed must keep nearly all the true inliers.
TEST(PnpRansac, PlanarSceneKeepsItsConsensus) {
  for (std::uint64_t seed = 0; seed < 20; ++seed) {
    std::mt19937_64 random(seed);
    std::uniform_real_distribution<double> unit(-1.0, 1.0);
    std::normal_distribution<double> noise(0.0, 0.7);
    std::vector<PnpCorrespondence> correspondences;
    std::vector<bool> is_inlier;
    for (int i = 0; i < 240; ++i) {
      // The plane z = 3 + 0.4 x in the camera frame, the camera at the world's origin.
      const double x = 1.5 * unit(random), y = unit(random);
      const Eigen::Vector3d point(x, y, 3.0 + 0.4 * x);
      const Eigen::Vector3d pixels = kCamera.Project(point);
      PnpCorrespondence c;
      c.world = point;
      c.pixel = Eigen::Vector2d(pixels.x() + noise(random), pixels.y() + noise(random));
      const bool outlier = i % 8 == 0;  // 30 of 240, 40 px off at most
      if (outlier) c.pixel += 40.0 * Eigen::Vector2d(unit(random), unit(random));
      correspondences.push_back(c);
      is_inlier.push_back(!outlier);
    }
    geometry::PnpRansacOptions options;
    options.kernel = PnpKernel::kAp3p;
    const geometry::PnpResult result =
        geometry::SolvePnpRansac(correspondences, kCamera, options, Eigen::Isometry3d::Identity());
    ASSERT_TRUE(result.success) << "seed " << seed;
    int true_inliers = 0;
    for (const int i : result.inliers) true_inliers += is_inlier[i] ? 1 : 0;
    // 0.7 px noise against a 2 px threshold: 99.8 % of the 210 true inliers fall inside at the
    // true pose; 90 % leaves room for a pose fitted to the noise.
    EXPECT_GE(true_inliers, 0.9 * 210) << "seed " << seed;
  }
}

TEST(PnpRansac, NamesAndTooFewPoints) {
  EXPECT_FALSE(geometry::ParsePnpKernel("DLS"));
  EXPECT_NE(geometry::PnpKernelNames().find("SQPNP"), std::string::npos);
  const Scene scene = MakeScene(1);
  const std::vector<PnpCorrespondence> few(scene.correspondences.begin(),
                                           scene.correspondences.begin() + 2);
  for (const std::string kernel : {"AP3P", "UMEYAMA"}) {
    geometry::PnpRansacOptions options;
    options.kernel = *geometry::ParsePnpKernel(kernel);
    EXPECT_FALSE(
        geometry::SolvePnpRansac(few, kCamera, options, Eigen::Isometry3d::Identity()).success);
  }
}

}  // namespace
}  // namespace stereo_fabmap_slam::test
