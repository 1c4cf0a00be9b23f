// The synthetic stereo world: exact geometry, determinism, readable output, and the odometry on it.
#include <filesystem>
#include <fstream>
#include <iterator>
#include <random>

#include <gtest/gtest.h>
#include <opencv2/calib3d.hpp>
#include <opencv2/imgproc.hpp>

#include "stereo_fabmap_slam/camera/stereo_rectifier.h"
#include "stereo_fabmap_slam/datasets/camera_renderer.h"
#include "stereo_fabmap_slam/datasets/euroc_sequence.h"
#include "stereo_fabmap_slam/datasets/synthetic_sequence.h"
#include "stereo_fabmap_slam/evaluation/trajectory_metrics.h"
#include "stereo_fabmap_slam/pipeline/stereo_slam.h"
#include "test_support.h"

namespace stereo_fabmap_slam::test {
namespace {

using namespace datasets;  // NOLINT: the module under test

// A dark room whose +x wall (x = 10, spanning y in [0, 10], z in [0, 5]) shows a 3 x 3 grid of
// white discs; returns the scene and the discs' world positions.
HallScene MarkerRoom(std::vector<Eigen::Vector3d>* discs) {
  const int width = 1000, height = 500;  // 100 texels per metre
  cv::Mat wall(height, width, CV_8UC1, cv::Scalar(0));
  for (const double y : {2.0, 5.0, 8.0}) {
    for (const double z : {1.0, 2.5, 4.0}) {
      // The wall's texture runs along +y from the left edge and down from the top (z = 5).
      const cv::Point2d centre(y * 100.0 - 0.5, (5.0 - z) * 100.0 - 0.5);
      cv::circle(wall, cv::Point(static_cast<int>(centre.x * 16), static_cast<int>(centre.y * 16)),
                 12 * 16, cv::Scalar(255), cv::FILLED, cv::LINE_AA, 4);
      discs->emplace_back(10.0, y, z);
    }
  }
  std::vector<Texture> textures = {
      TextureLibrary::FromImage(wall, "markers"),
      TextureLibrary::FromImage(cv::Mat(8, 8, CV_8UC1, cv::Scalar(0)), "black")};
  Box room;
  room.min = Eigen::Vector3f(0, 0, 0);
  room.max = Eigen::Vector3f(10, 10, 5);
  for (int face = 0; face < 6; ++face) room.faces[face] = Material{{face == 1 ? 0 : 1}, 1, 1, 1.0f};
  return HallScene({room}, textures);
}

// Centroids of bright blobs (grey-level weighted).
std::vector<cv::Point2d> BlobCentroids(const cv::Mat& radiance) {
  cv::Mat mask;
  cv::threshold(radiance, mask, 20.0, 255, cv::THRESH_BINARY);
  mask.convertTo(mask, CV_8U);
  cv::Mat labels;
  const int count = cv::connectedComponents(mask, labels);
  std::vector<cv::Point3d> sums(static_cast<std::size_t>(count), cv::Point3d(0, 0, 0));
  for (int v = 0; v < radiance.rows; ++v) {
    for (int u = 0; u < radiance.cols; ++u) {
      const int label = labels.at<int>(v, u);
      if (label == 0) continue;
      const double w = radiance.at<float>(v, u);
      sums[static_cast<std::size_t>(label)] += cv::Point3d(w * u, w * v, w);
    }
  }
  std::vector<cv::Point2d> centroids;
  for (int label = 1; label < count; ++label) {
    const cv::Point3d& s = sums[static_cast<std::size_t>(label)];
    centroids.emplace_back(s.x / s.z, s.y / s.z);
  }
  return centroids;
}

double NearestDistance(const std::vector<cv::Point2d>& points, const cv::Point2d& p,
                       cv::Point2d* nearest) {
  double best = 1e9;
  for (const cv::Point2d& q : points) {
    if (cv::norm(q - p) < best) {
      best = cv::norm(q - p);
      *nearest = q;
    }
  }
  return best;
}

Eigen::Isometry3d BodyLookingAtMarkers() {
  Eigen::Isometry3d body = Eigen::Isometry3d::Identity();
  body.linear() = (Eigen::AngleAxisd(0.08, Eigen::Vector3d::UnitZ()) *
                   Eigen::AngleAxisd(-0.05, Eigen::Vector3d::UnitY()) *
                   Eigen::AngleAxisd(0.04, Eigen::Vector3d::UnitX()))
                      .toRotationMatrix();
  body.translation() = Eigen::Vector3d(4.5, 5.1, 2.4);
  return body;
}

TEST(SyntheticWorld, MarkersAppearWhereTheCalibrationProjectsThem) {
  std::vector<Eigen::Vector3d> discs;
  const HallScene scene = MarkerRoom(&discs);
  const camera::StereoCalibration rig = SyntheticSequence::Rig(/*distortion=*/true);
  const Eigen::Isometry3d body = BodyLookingAtMarkers();
  for (const camera::CameraCalibration* camera : {&rig.left, &rig.right}) {
    const Eigen::Isometry3d T_world_camera = body * camera->T_body_camera;
    const std::vector<cv::Point2d> found =
        BlobCentroids(CameraRenderer(*camera).Render(scene, T_world_camera));
    ASSERT_EQ(found.size(), discs.size());
    // Project the disc centres with OpenCV and the same calibration.
    std::vector<cv::Point3d> object;
    const Eigen::Isometry3d T_camera_world = T_world_camera.inverse();
    for (const Eigen::Vector3d& d : discs) {
      const Eigen::Vector3d c = T_camera_world * d;
      object.emplace_back(c.x(), c.y(), c.z());
    }
    std::vector<cv::Point2d> projected;
    cv::projectPoints(object, cv::Vec3d(0, 0, 0), cv::Vec3d(0, 0, 0), camera->CameraMatrix(),
                      camera->distortion, projected);
    for (const cv::Point2d& p : projected) {
      cv::Point2d nearest;
      // A 24 cm disc seen from 5.5 m spans ~20 px; its centroid sits within a few hundredths of
      // a pixel of the projected centre (perspective and distortion shift it very slightly).
      EXPECT_LT(NearestDistance(found, p, &nearest), 0.15) << "projected at " << p;
    }
  }
}

TEST(SyntheticWorld, RectifiedDisparityMatchesDepth) {
  std::vector<Eigen::Vector3d> discs;
  const HallScene scene = MarkerRoom(&discs);
  const camera::StereoCalibration rig = SyntheticSequence::Rig(true);
  const camera::StereoRectifier rectifier = camera::StereoRectifier::FromCalibration(rig);
  const Eigen::Isometry3d body = BodyLookingAtMarkers();
  const auto render = [&](const camera::CameraCalibration& c) {
    cv::Mat image;
    CameraRenderer(c).Render(scene, body * c.T_body_camera).convertTo(image, CV_8U);
    return image;
  };
  cv::Mat left, right;
  rectifier.Rectify(render(rig.left), render(rig.right), &left, &right);
  cv::Mat left_float, right_float;
  left.convertTo(left_float, CV_32F);
  right.convertTo(right_float, CV_32F);
  const std::vector<cv::Point2d> in_left = BlobCentroids(left_float),
                                 in_right = BlobCentroids(right_float);
  ASSERT_EQ(in_left.size(), discs.size());
  const Eigen::Isometry3d T_rectified_world = (body * rectifier.T_body_rectified_left()).inverse();
  const geometry::StereoCamera& camera = rectifier.camera();
  for (const Eigen::Vector3d& disc : discs) {
    const Eigen::Vector3d c = T_rectified_world * disc;
    const Eigen::Vector3d expected = camera.Project(c);
    cv::Point2d l, r;
    ASSERT_LT(NearestDistance(in_left, {expected.x(), expected.y()}, &l), 0.3);
    ASSERT_LT(NearestDistance(in_right, {expected.z(), expected.y()}, &r), 0.3);
    EXPECT_NEAR(l.y, r.y, 0.2);  // same row after rectification
    // Depth from disparity: 0.2 px of centroid error at ~9 px disparity is ~2 %.
    EXPECT_NEAR(camera.DepthFromDisparity(l.x - r.x), c.z(), 0.03 * c.z());
  }
}

std::string FileBytes(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  return std::string(std::istreambuf_iterator<char>(in), {});
}

// The renderer traces, for each tile of pixels, only the obstacles in the tile's cone of rays
// (HallScene::ObstaclesInCone). That must see what tracing every obstacle sees: rays drawn in
// random cones from random points of the hall, half of them at the cone's rim, give the same
// grey level either way; and the cull is no no-op (it drops obstacles, rays do hit them).
TEST(SyntheticWorld, ObstaclesInAConeAreAllThatItsRaysCanHit) {
  const HallScene scene(HallOptions{},
                        TextureLibrary::Load(SyntheticSequenceOptions{}.photo_folder), 1);
  const int obstacles = static_cast<int>(scene.boxes().size()) - 1;
  ASSERT_GT(obstacles, 0);
  const std::vector<int> none;
  std::mt19937 random(5);
  std::uniform_real_distribution<float> unit(0.0f, 1.0f);
  const auto random_unit_vector = [&] {
    std::normal_distribution<float> normal;
    return Eigen::Vector3f(normal(random), normal(random), normal(random)).normalized();
  };
  const HallOptions& hall = scene.options();
  int rays = 0, rays_on_obstacles = 0, obstacles_dropped = 0;
  for (int cone = 0; cone < 2000; ++cone) {
    const Eigen::Vector3f origin(0.2f + unit(random) * (hall.length - 0.4f),
                                 0.2f + unit(random) * (hall.width - 0.4f),
                                 0.2f + unit(random) * (hall.height - 0.4f));
    const Eigen::Vector3f axis = random_unit_vector();
    // A 16-pixel tile of the EuRoC lens spans up to ~0.03 rad from its centre ray.
    const float half_angle = 0.002f + 0.1f * unit(random);
    const std::vector<int> in_cone = scene.ObstaclesInCone(origin, axis, half_angle);
    obstacles_dropped += obstacles - static_cast<int>(in_cone.size());
    for (int r = 0; r < 20; ++r) {
      const Eigen::Vector3f across = axis.cross(random_unit_vector()).normalized();
      const float angle = half_angle * (r % 2 == 0 ? 1.0f : unit(random));
      const Eigen::Vector3f direction = Eigen::AngleAxisf(angle, across) * axis;
      const float everything = scene.Trace(origin, direction, 0.002f, nullptr);
      ASSERT_EQ(scene.Trace(origin, direction, 0.002f, &in_cone), everything)
          << "cone " << cone << " ray " << r;
      rays_on_obstacles += scene.Trace(origin, direction, 0.002f, &none) != everything ? 1 : 0;
      ++rays;
    }
  }
  // Measured: 3,415 of 40,000 rays end on an obstacle; 22,835 of 24,000 obstacles dropped.
  EXPECT_GT(rays_on_obstacles, rays / 20);
  EXPECT_GT(obstacles_dropped, 2000 * obstacles / 2);
  RecordProperty("rays_on_obstacles", rays_on_obstacles);
  RecordProperty("obstacles_dropped", obstacles_dropped);
}

TEST(SyntheticWorld, SameSeedSameBytesAndReadableOutput) {
  TemporaryDirectory temp;
  SyntheticSequenceOptions options;
  options.seconds = 0.5;
  options.route = "figure8";
  SyntheticSequence(options).Write(temp.path() + "/a");
  SyntheticSequence(options).Write(temp.path() + "/b");
  options.seed = 2;
  SyntheticSequence(options).Write(temp.path() + "/c");
  int compared = 0;
  for (const auto& entry : std::filesystem::recursive_directory_iterator(temp.path() + "/a")) {
    if (!entry.is_regular_file()) continue;
    const std::filesystem::path relative =
        std::filesystem::relative(entry.path(), temp.path() + "/a");
    EXPECT_EQ(FileBytes(entry.path()), FileBytes(temp.path() + "/b/" + relative.string()))
        << relative;
    ++compared;
  }
  // Images, lists, sensor.yaml files, ground truth, synthetic.yaml, stereo_calibration.yaml.
  EXPECT_EQ(compared, 2 * 10 + 2 + 2 + 1 + 1 + 1);
  const std::string first =
      "/mav0/cam0/data/" + std::to_string(SyntheticSequence::kStartNs) + ".png";
  EXPECT_NE(FileBytes(temp.path() + "/a" + first), FileBytes(temp.path() + "/c" + first));

  // The package's own reader takes it, calibration and ground truth included.
  const datasets::EurocSequence sequence = datasets::EurocSequence::Open(temp.path() + "/a");
  EXPECT_EQ(sequence.size(), 10u);
  EXPECT_TRUE(sequence.unpaired().empty());
  const camera::StereoCalibration rig = SyntheticSequence::Rig(true);
  EXPECT_NEAR(sequence.calibration().left.fx, rig.left.fx, 1e-12);
  EXPECT_NEAR(sequence.calibration().right.distortion[0], rig.right.distortion[0], 1e-12);
  EXPECT_TRUE(sequence.calibration().right.T_body_camera.isApprox(rig.right.T_body_camera, 1e-12));
  EXPECT_NEAR(sequence.calibration().T_right_left().translation().norm(), 0.11, 1e-9);
  ASSERT_EQ(sequence.ground_truth().size(), 91u);  // 0.45 s at 200 Hz, both ends included
  const Route route(RouteKind::kFigure8, HallOptions{});
  EXPECT_TRUE(sequence.ground_truth()[40].pose.isApprox(route.BodyPose(0.2), 1e-6));
  EXPECT_NO_THROW(sequence.LoadStereoPair(9));
  // The nodelets' calibration file describes the same rig.
  const camera::StereoCalibration written =
      camera::ReadStereoCalibrationYaml(temp.path() + "/a/stereo_calibration.yaml");
  EXPECT_TRUE(written.T_right_left().isApprox(rig.T_right_left(), 1e-12));
  EXPECT_NEAR(written.right.cy, rig.right.cy, 1e-12);
}

TEST(SyntheticWorld, ExposureAndMotionBlurChangeTheImages) {
  TemporaryDirectory temp;
  SyntheticSequenceOptions options;
  options.seconds = 1.6;  // the exposure gain swings over 6 s: by 1.5 s it is ~20 % up
  options.noise_sigma = 0.0;
  SyntheticSequence(options).Write(temp.path() + "/plain");
  options.exposure_changes = true;
  SyntheticSequence(options).Write(temp.path() + "/exposure");
  options.exposure_changes = false;
  options.motion_blur = true;
  SyntheticSequence(options).Write(temp.path() + "/blur");
  const datasets::EurocSequence plain = datasets::EurocSequence::Open(temp.path() + "/plain");
  const datasets::EurocSequence exposure = datasets::EurocSequence::Open(temp.path() + "/exposure");
  const datasets::EurocSequence blur = datasets::EurocSequence::Open(temp.path() + "/blur");
  const std::size_t last = plain.size() - 1;
  const cv::Mat a = plain.LoadStereoPair(last).left, b = exposure.LoadStereoPair(last).left;
  EXPECT_GT(cv::mean(b)[0], 1.1 * cv::mean(a)[0]);  // brighter by the gain
  // Blur keeps the brightness but removes fine detail: less gradient energy.
  const auto sharpness = [](const cv::Mat& image) {
    cv::Mat laplacian;
    cv::Laplacian(image, laplacian, CV_32F);
    return cv::mean(cv::abs(laplacian))[0];
  };
  const cv::Mat c = blur.LoadStereoPair(last).left;
  EXPECT_NEAR(cv::mean(c)[0], cv::mean(a)[0], 0.02 * cv::mean(a)[0]);
  EXPECT_LT(sharpness(c), sharpness(a));
}

TEST(SyntheticWorld, KidnapRouteJumpsBackToAPlaceSeenBefore) {
  Route route(RouteKind::kKidnap, HallOptions{});
  route.set_duration(40.0);
  ASSERT_TRUE(route.cut_time());
  const double cut = *route.cut_time();
  const Eigen::Isometry3d before = route.BodyPose(cut - 0.05), after = route.BodyPose(cut);
  EXPECT_GT((after.translation() - before.translation()).norm(), 2.0);  // a jump, not a step
  // ... to exactly where it was `jump` seconds earlier, which lies inside the sequence.
  EXPECT_GT(cut - route.jump(), 0.0);
  EXPECT_TRUE(after.isApprox(route.BodyPose(cut - route.jump()), 1e-12));
  // Elsewhere the route moves smoothly at walking speed.
  for (double t = 0.0; t + 0.05 < cut; t += 0.05) {
    const double speed =
        (route.BodyPose(t + 0.05).translation() - route.BodyPose(t).translation()).norm() / 0.05;
    EXPECT_GT(speed, 0.3);
    EXPECT_LT(speed, 2.0);
  }
}

TEST(SyntheticWorld, OdometryOnARenderedLoop) {
  TemporaryDirectory temp;
  SyntheticSequenceOptions options;
  options.seconds = 12.0;
  SyntheticSequence(options).Write(temp.path());
  const datasets::EurocSequence sequence = datasets::EurocSequence::Open(temp.path());
  const camera::StereoRectifier rectifier =
      camera::StereoRectifier::FromCalibration(sequence.calibration());
  pipeline::StereoSlam odometry(pipeline::FrontEndOptions{}, backend::BundleAdjustmentOptions{},
                                rectifier, [] { return 0.0; });
  int tracked = 0;
  for (std::size_t i = 0; i < sequence.size(); ++i) {
    const datasets::StereoImages images = sequence.LoadStereoPair(i);
    const pipeline::FrameRecord* frame =
        odometry.ProcessFrame(images.timestamp_ns * 1e-9, images.left, images.right);
    tracked += frame != nullptr && frame->state != odometry::TrackingState::kLost ? 1 : 0;
  }
  EXPECT_EQ(tracked, static_cast<int>(sequence.size()));
  const evaluation::Trajectory truth = evaluation::TransformToSensorFrame(
      sequence.ground_truth(), rectifier.T_body_rectified_left());
  const evaluation::EvaluationResult result = evaluation::EvaluateTrajectory(
      truth, odometry.OdometryTrajectory(), evaluation::EvaluationOptions{});
  RecordProperty("ate_rmse_m", std::to_string(result.ate.rmse));
  EXPECT_EQ(result.matched, sequence.size());
  EXPECT_LT(result.ate.rmse, 0.03);
}

}  // namespace
}  // namespace stereo_fabmap_slam::test
