// The office floor: a rendered world with the perceptual aliasing of a real building (identical
// doors, blank walls), exact geometry, routes that keep to its corridors.
#include <cmath>
#include <cstdint>
#include <vector>

#include <gtest/gtest.h>

#include "stereo_fabmap_slam/datasets/camera_renderer.h"
#include "stereo_fabmap_slam/datasets/euroc_sequence.h"
#include "stereo_fabmap_slam/datasets/office_floor.h"
#include "stereo_fabmap_slam/datasets/rounded_path.h"
#include "stereo_fabmap_slam/datasets/synthetic_sequence.h"
#include "stereo_fabmap_slam/evaluation/place_ground_truth.h"
#include "test_support.h"

namespace stereo_fabmap_slam::test {
namespace {

using namespace datasets;  // NOLINT: the module under test

TEST(RoundedPath, ARectangleWithRoundedCornersIsWalkedAtItsLength) {
  // 10 x 4 m, corners of 1 m: each corner saves 2 m of legs and adds a quarter circle.
  const RoundedPath path({{0, 0}, {10, 0}, {10, 4}, {0, 4}}, 1.0);
  EXPECT_NEAR(path.length(), 28.0 - 4 * (2.0 - M_PI / 2), 1e-9);
  // The path is continuous and its direction is the derivative of its position, everywhere
  // (1 mm steps: a chord differs from the arc by far less than the 1e-4 tolerance).
  for (double s = -3.0; s < path.length() + 3.0; s += 0.01) {
    const Eigen::Vector2d step = path.Position(s + 1e-3) - path.Position(s);
    EXPECT_NEAR(step.norm(), 1e-3, 1e-7) << s;
    EXPECT_NEAR(path.Direction(s).norm(), 1.0, 1e-12);
    EXPECT_LT((step / 1e-3 - path.Direction(s + 0.5e-3)).norm(), 1e-4) << s;
  }
  // The first corner's arc starts 1 m before the waypoint and its middle keeps r (sqrt 2 - 1)
  // from the corner, on the inside.
  EXPECT_TRUE(path.Position(0).isApprox(Eigen::Vector2d(0, 1), 1e-12));
  EXPECT_NEAR(path.Position(M_PI / 4).norm(), std::sqrt(2.0) - 1.0, 1e-9);
  EXPECT_THROW(RoundedPath({{0, 0}, {1, 0}, {1, 4}}, 1.0), std::invalid_argument);  // too short
  EXPECT_THROW(RoundedPath({{0, 0}, {0, 0}, {1, 4}}, 0.1), std::invalid_argument);
}

// Every route keeps clear of every wall and piece of furniture: a walker's body needs 0.4 m.
TEST(OfficeWorld, RoutesKeepToTheCorridors) {
  const OfficeOptions office;
  const HallScene scene = OfficeFloor::Scene(office, 1);
  for (const RouteKind kind : {RouteKind::kLoop, RouteKind::kFigure8}) {
    const Route route(kind, OfficeFloor::Path(kind, office));
    double closest = 1e9;
    for (double t = 0; t < route.lap_time(); t += 0.05) {
      const Eigen::Vector3d position = route.BodyPose(t).translation();
      for (int axis = 0; axis < 2; ++axis) {
        closest = std::min({closest, position[axis] - scene.boxes()[0].min[axis],
                            scene.boxes()[0].max[axis] - position[axis]});
      }
      EXPECT_LT(position.z(), office.height - 0.9) << t;
      for (std::size_t b = 1; b < scene.boxes().size(); ++b) {
        const Box& box = scene.boxes()[b];
        const Eigen::Vector2d nearest(std::clamp<double>(position.x(), box.min.x(), box.max.x()),
                                      std::clamp<double>(position.y(), box.min.y(), box.max.y()));
        closest = std::min(closest, (nearest - position.head<2>()).norm());
      }
    }
    EXPECT_GE(closest, 0.4) << RouteKindName(kind);
  }
  // The loop comes back to its start after a lap (80 m at 1 m/s); the figure of eight walks
  // the middle corridor twice in the same direction, half a lap apart.
  const Route loop(RouteKind::kLoop, OfficeFloor::Path(RouteKind::kLoop, office));
  EXPECT_NEAR(loop.lap_time(), 2 * (28 + 13) - 4 * (2 - M_PI / 2), 1e-9);
  const std::vector<double> loop_revisits = loop.Revisits(loop.lap_time() + 10);
  ASSERT_EQ(loop_revisits.size(), 1u);
  EXPECT_NEAR(loop_revisits[0], loop.lap_time() - 1.0, 0.15);  // 1 m before the start
  const Route eight(RouteKind::kFigure8, OfficeFloor::Path(RouteKind::kFigure8, office));
  const std::vector<double> eight_revisits = eight.Revisits(eight.lap_time());
  ASSERT_FALSE(eight_revisits.empty());
  EXPECT_NEAR(eight.BodyPose(eight_revisits[0]).translation().x(), 0.5 * office.length, 0.5);
}

// The world has the aliasing of a real building, and its ground truth does not: the same door
// 9 m further along the same wall renders to the same pixels, yet is another place.
TEST(OfficeWorld, IdenticalDoorsLookAlikeButAreDifferentPlaces) {
  const OfficeOptions office;
  const HallScene scene = OfficeFloor::Scene(office, 1);
  const camera::StereoCalibration rig = SyntheticSequence::Rig(/*distortion=*/false);
  const CameraRenderer renderer(rig.left);
  // Facing the outer wall (y = 0) from the corridor, 1.9 m away. Its 20 panels of 1.5 m carry a
  // door on every third (centres 6.75, 11.25, ..., 24.75 m; the first is the exit).
  const auto camera_facing_wall_at = [&](double x) {
    Eigen::Isometry3d body = Eigen::Isometry3d::Identity();
    body.linear() = Eigen::AngleAxisd(-M_PI / 2, Eigen::Vector3d::UnitZ()).toRotationMatrix();
    body.translation() = Eigen::Vector3d(x, 1.9, 1.2);
    return body * rig.left.T_body_camera;
  };
  const cv::Rect door_leaf(static_cast<int>(rig.left.cx) - 80, static_cast<int>(rig.left.cy) - 150,
                           160, 300);
  const auto difference = [&](double x0, double x1) {
    const cv::Mat a = renderer.Render(scene, camera_facing_wall_at(x0));
    const cv::Mat b = renderer.Render(scene, camera_facing_wall_at(x1));
    return cv::mean(cv::abs(a(door_leaf) - b(door_leaf)))[0];
  };
  // Two doors 9 m apart: within a grey level (the textures are one; bilinear sampling at the
  // same offsets gives the same values). A door against a painted panel: tens of levels.
  EXPECT_LT(difference(11.25, 20.25), 1.0);
  EXPECT_GT(difference(11.25, 13.5), 40.0);

  // Ground truth from the poses and the wall's geometry: the wall's points in view (a grid on
  // y = 0 within 2 m of the camera's axis), carried between the cameras.
  geometry::StereoCamera camera;
  camera.size = rig.left.resolution;
  camera.fx = rig.left.fx, camera.fy = rig.left.fy, camera.cx = rig.left.cx,
  camera.cy = rig.left.cy;
  camera.baseline = 0.11;
  std::vector<std::vector<Eigen::Vector3d>> points;
  std::vector<std::optional<Eigen::Isometry3d>> poses;
  for (const double x : {11.25, 11.55, 20.25}) {
    const Eigen::Isometry3d T_world_camera = camera_facing_wall_at(x);
    std::vector<Eigen::Vector3d> wall;
    for (double u = -2.0; u <= 2.0; u += 0.25) {
      for (double z = 0.2; z <= 2.5; z += 0.25) {
        const Eigen::Vector3d point = T_world_camera.inverse() * Eigen::Vector3d(x + u, 0.0, z);
        const double column = camera.cx + camera.fx * point.x() / point.z();
        const double row = camera.cy + camera.fy * point.y() / point.z();
        if (column >= 0 && column < camera.size.width && row >= 0 && row < camera.size.height)
          wall.push_back(point);
      }
    }
    points.push_back(wall);
    poses.push_back(T_world_camera);
  }
  const evaluation::PlaceGroundTruth truth =
      evaluation::PlaceGroundTruth::FromPoses(points, poses, camera, 0.5);
  EXPECT_TRUE(truth.Same(0, 1));   // 0.3 m along the wall: the same place
  EXPECT_FALSE(truth.Same(0, 2));  // the identical door 9 m on: not
}

// Each seed is another building: its own door design (and company name), so that a vocabulary
// trained on one rendered office meets new doors in the next, as it does in a real building.
// The design is a few discrete choices (finish, glass, kick plate, handle, hinge side, frame:
// 360 designs), so two seeds may share one now and then (seeds 1 and 3 do); the wood grain
// still differs, but only by a few grey levels. Among eight seeds, most pairs must differ by
// more than that.
TEST(OfficeWorld, EachSeedIsABuildingWithItsOwnDoor) {
  const OfficeOptions office;
  const camera::StereoCalibration rig = SyntheticSequence::Rig(/*distortion=*/false);
  const CameraRenderer renderer(rig.left);
  Eigen::Isometry3d body = Eigen::Isometry3d::Identity();
  body.linear() = Eigen::AngleAxisd(-M_PI / 2, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  body.translation() = Eigen::Vector3d(11.25, 1.9, 1.2);  // facing a door of the outer wall
  // The whole door, frame to frame (0.96 m at 1.9 m: 232 pixels), and the image's height
  // (0.17-2.23 m above the floor): leaf, frame, glass, handle, hinges.
  const cv::Rect door(static_cast<int>(rig.left.cx) - 125, 0, 250, rig.left.resolution.height);
  std::vector<cv::Mat> doors;
  for (std::uint64_t seed = 1; seed <= 8; ++seed) {
    cv::Mat view = renderer.Render(OfficeFloor::Scene(office, seed), body * rig.left.T_body_camera);
    cv::Mat leaf;
    view(door).convertTo(leaf, CV_32F);
    doors.push_back(leaf);
  }
  int pairs = 0, different = 0;
  for (std::size_t a = 0; a < doors.size(); ++a) {
    for (std::size_t b = a + 1; b < doors.size(); ++b, ++pairs) {
      // 5 grey levels on average over the door: measured on seeds 1-8, 27 pairs differ by
      // 10.5 or more, the one pair with the same design (seeds 1 and 3) by 2.6, the grain.
      if (cv::mean(cv::abs(doors[a] - doors[b]))[0] > 5.0) ++different;
    }
  }
  // Two seeds draw the same design with probability 1/360: of 28 pairs, one coinciding is
  // already unlikely (8 %), four would mean the seed hardly draws the design.
  EXPECT_GE(different, pairs - 3);
}

TEST(OfficeWorld, SameSeedSameBytesAtAnyResolution) {
  TemporaryDirectory temp;
  SyntheticSequenceOptions options = SyntheticSequenceOptions::ForScene("office");
  EXPECT_TRUE(options.auto_exposure);
  options.seconds = 0.3;
  options.resolution = cv::Size(512, 384);
  SyntheticSequence(options).Write(temp.path() + "/a");
  SyntheticSequence(options).Write(temp.path() + "/b");
  const std::string first =
      "/mav0/cam0/data/" + std::to_string(SyntheticSequence::kStartNs) + ".png";
  EXPECT_EQ(ReadTextFile(temp.path() + "/a" + first), ReadTextFile(temp.path() + "/b" + first));
  options.seed = 2;  // other posters, notice boards, art and paint
  SyntheticSequence(options).Write(temp.path() + "/c");
  EXPECT_NE(ReadTextFile(temp.path() + "/a" + first), ReadTextFile(temp.path() + "/c" + first));

  // 512 x 384 with the field of view of the 752 x 480 rig, read back as any sequence.
  const EurocSequence sequence = EurocSequence::Open(temp.path() + "/a");
  ASSERT_EQ(sequence.size(), 6u);
  const camera::StereoCalibration full = SyntheticSequence::Rig(true);
  const camera::CameraCalibration& left = sequence.calibration().left;
  EXPECT_EQ(left.resolution, cv::Size(512, 384));
  EXPECT_NEAR(std::atan(0.5 * 512 / left.fx), std::atan(0.5 * 752 / full.left.fx), 1e-9);
  EXPECT_NEAR(left.fx / left.fy, full.left.fx / full.left.fy, 1e-12);
  // Auto exposure brings every image to about mid grey (118), whatever the view holds: within
  // the spread that clipped ceiling lights and the 2-level noise leave.
  for (std::size_t i = 0; i < sequence.size(); ++i) {
    const datasets::StereoImages images = sequence.LoadStereoPair(i);
    EXPECT_EQ(images.left.size(), cv::Size(512, 384));
    EXPECT_NEAR(cv::mean(images.left)[0], 118, 12) << i;
    EXPECT_NEAR(cv::mean(images.right)[0], 118, 12) << i;
  }
}

}  // namespace
}  // namespace stereo_fabmap_slam::test
