// The DenseMapper's plumbing: its messages handed to the dense mapping stage as run_dataset
// hands it the same inputs (pairs by stamp, keyframes with their odometry pose, the map).
#include <cstdint>
#include <optional>
#include <string>

#include <gtest/gtest.h>
#include <boost/make_shared.hpp>

#include "dense_wiring.h"
#include "ros_conversions.h"
#include "stereo_fabmap_slam/datasets/synthetic_sequence.h"

namespace stereo_fabmap_slam::test {
namespace {

sensor_msgs::ImageConstPtr ImageAt(const ros::Time& stamp, const cv::Size& size,
                                   const std::string& encoding = "mono8") {
  auto image = boost::make_shared<sensor_msgs::Image>();
  image->header.stamp = stamp;
  image->width = static_cast<std::uint32_t>(size.width);
  image->height = static_cast<std::uint32_t>(size.height);
  image->encoding = encoding;
  image->step = image->width * (encoding == "mono8" ? 1 : 4);
  image->data.assign(image->step * image->height, 100);
  return image;
}

TEST(DenseWiring, MessagesReachTheStageAsTheirStructs) {
  const camera::StereoCalibration rig = datasets::SyntheticSequence::Rig(true);
  const camera::StereoRectifier rectifier =
      camera::StereoRectifier::FromCalibration(rig, camera::RectificationOptions());
  dense::DenseMappingStage stage(dense::DenseMappingOptions(), dense::StereoDepthOptions(),
                                 dense::FusionOptions(), rectifier);
  const ros::Time stamp(12, 500);
  const cv::Size size = rig.left.resolution;

  // Not an image the stage can take: refused with a reason, nothing handed over.
  const auto not_grey = ImageAt(stamp, size, "32FC1");
  std::string refusal;
  EXPECT_FALSE(ros_wiring::DenseInputOf(ros_wiring::ImagePair{not_grey, not_grey, 1}, &refusal));
  EXPECT_FALSE(refusal.empty());

  // The pair, then its keyframe (by the stamp's nanoseconds) with its odometry pose.
  refusal.clear();
  const std::optional<dense::DenseInput> pair = ros_wiring::DenseInputOf(
      ros_wiring::ImagePair{ImageAt(stamp, size), ImageAt(stamp, size), 2}, &refusal);
  ASSERT_TRUE(pair.has_value());
  EXPECT_EQ(refusal, "");
  stage.Add(*pair);
  auto keyframe = boost::make_shared<stereo_fabmap_slam::Keyframe>();
  keyframe->header.stamp = stamp;
  keyframe->id = 7;
  const Eigen::Isometry3d T_odom_camera(Eigen::Translation3d(1.0, 2.0, 0.5));
  keyframe->pose = ros_conversions::ToPoseMessage(T_odom_camera);
  stage.Add(ros_wiring::DenseInputOf(*keyframe));
  dense::DenseStepReport report = stage.Step();
  ASSERT_EQ(report.fused.size(), 1u);
  EXPECT_EQ(report.fused[0].id, 7u);

  // map_graph: map -> odom and the map poses. The keyframe where odometry put it does not move;
  // 10 cm away it does.
  auto graph = boost::make_shared<stereo_fabmap_slam::MapGraph>();
  graph->map_to_odom = ros_conversions::ToTransformMessage(Eigen::Isometry3d::Identity());
  graph->keyframe_ids = {7};
  graph->keyframe_poses = {ros_conversions::ToPoseMessage(T_odom_camera)};
  stage.Add(ros_wiring::DenseInputOf(*graph));
  EXPECT_EQ(stage.Step().moved, 0u);
  graph = boost::make_shared<stereo_fabmap_slam::MapGraph>(*graph);
  graph->keyframe_poses[0].position.x += 0.1;
  stage.Add(ros_wiring::DenseInputOf(*graph));
  EXPECT_EQ(stage.Step().moved, 1u);
}

}  // namespace
}  // namespace stereo_fabmap_slam::test
