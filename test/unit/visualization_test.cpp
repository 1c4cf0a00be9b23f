// The Visualizer's drawing (src/ros/): markers of a hand-built graph with two map segments, a
// loop and a relocalization; the corrected path bending with its keyframes; the bounded cloud;
// the tracking image's colours.
#include <filesystem>
#include <regex>
#include <set>
#include <string>

#include <gtest/gtest.h>
#include <sensor_msgs/point_cloud2_iterator.h>
#include <yaml-cpp/yaml.h>

#include "map_cloud.h"
#include "map_markers.h"
#include "ros_conversions.h"
#include "test_support.h"
#include "tracking_image.h"
#include "trajectory_paths.h"

namespace stereo_fabmap_slam::test {
namespace {

using stereo_fabmap_slam::MapGraph;
using stereo_fabmap_slam::MapGraphEdge;

Eigen::Isometry3d At(double x, double y = 0) {
  Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
  pose.translation() = Eigen::Vector3d(x, y, 0);
  return pose;
}

MapGraphEdge Edge(std::uint64_t from, std::uint64_t to, std::uint8_t type) {
  MapGraphEdge edge;
  edge.from_id = from;
  edge.to_id = to;
  edge.type = type;
  return edge;
}

// Keyframes 0-2 (one piece of odometry), 5-6 (a second piece after a loss, found in the map by
// a relocalization 1 -> 5); a loop 0 -> 2.
MapGraph TwoSegmentGraph() {
  MapGraph graph;
  graph.header.frame_id = "map";
  for (std::uint64_t id : {0, 1, 2, 5, 6}) {
    graph.keyframe_ids.push_back(id);
    graph.keyframe_poses.push_back(ros_conversions::ToPoseMessage(At(static_cast<double>(id))));
  }
  graph.edges = {Edge(0, 1, MapGraphEdge::ODOMETRY), Edge(1, 2, MapGraphEdge::ODOMETRY),
                 Edge(5, 6, MapGraphEdge::ODOMETRY), Edge(0, 2, MapGraphEdge::LOOP),
                 Edge(1, 5, MapGraphEdge::RELOCALIZATION)};
  graph.map_to_odom.rotation.w = 1;
  return graph;
}

const visualization_msgs::Marker& Find(const visualization_msgs::MarkerArray& array,
                                       const std::string& name) {
  for (const auto& marker : array.markers) {
    if (marker.ns == name) return marker;
  }
  throw std::runtime_error("no marker " + name);
}

TEST(MapMarkers, SegmentsFollowOdometryEdges) {
  const std::map<std::uint64_t, int> segments = ros_visualization::MapSegments(TwoSegmentGraph());
  EXPECT_EQ(segments.at(0), 0);
  EXPECT_EQ(segments.at(2), 0);
  EXPECT_EQ(segments.at(5), 1);
  EXPECT_EQ(segments.at(6), 1);
}

TEST(MapMarkers, CountsMatchTheGraph) {
  const visualization_msgs::MarkerArray array =
      ros_visualization::MapGraphMarkers(TwoSegmentGraph(), ros_visualization::MarkerStyle());
  ASSERT_EQ(array.markers.size(), 5u);
  const auto& keyframes = Find(array, ros_visualization::kKeyframesNamespace);
  EXPECT_EQ(keyframes.points.size(), 5u * 2 * ros_visualization::kFrustumSegments);
  EXPECT_EQ(keyframes.colors.size(), keyframes.points.size());
  // Two segments, two colours.
  EXPECT_NE(keyframes.colors.front().r, keyframes.colors.back().r);
  EXPECT_EQ(Find(array, ros_visualization::kOdometryEdgesNamespace).points.size(), 6u);
  const auto& loops = Find(array, ros_visualization::kLoopEdgesNamespace);
  ASSERT_EQ(loops.points.size(), 2u);
  EXPECT_DOUBLE_EQ(loops.points[1].x, 2.0);
  EXPECT_GT(loops.color.r, 0.9);  // loops red
  EXPECT_LT(loops.color.b, 0.2);
  EXPECT_GT(Find(array, ros_visualization::kOdometryEdgesNamespace).color.b, 0.9);  // blue
  EXPECT_EQ(Find(array, ros_visualization::kRelocalizationEdgesNamespace).points.size(), 2u);
  const auto& relocalized = Find(array, ros_visualization::kRelocalizedNamespace);
  ASSERT_EQ(relocalized.points.size(), 1u);
  EXPECT_DOUBLE_EQ(relocalized.points[0].x, 5.0);  // the found piece's keyframe
  for (const auto& marker : array.markers) EXPECT_EQ(marker.header.frame_id, "map");
}

TEST(MapMarkers, NothingToDrawDeletes) {
  MapGraph graph = TwoSegmentGraph();
  graph.edges.resize(3);  // odometry only
  const visualization_msgs::MarkerArray array =
      ros_visualization::MapGraphMarkers(graph, ros_visualization::MarkerStyle());
  EXPECT_EQ(Find(array, ros_visualization::kLoopEdgesNamespace).action,
            visualization_msgs::Marker::DELETE);
  EXPECT_EQ(Find(array, ros_visualization::kKeyframesNamespace).action,
            visualization_msgs::Marker::ADD);
}

// Keyframes are cameras mounted on the base (turned and offset); the graph turns keyframe 1's
// camera by 90 degrees about the map's z axis through the origin (a loop closure): the base
// poses of the frames tracked after it turn with it, the earlier ones stay.
TEST(TrajectoryPaths, TheMapPathTurnsWithItsKeyframe) {
  Eigen::Isometry3d mount = Eigen::Isometry3d::Identity();
  mount.linear() << 0, 0, 1, -1, 0, 0, 0, -1, 0;
  mount.translation() = Eigen::Vector3d(0.2, 0.1, 0.5);
  Eigen::Isometry3d turn = Eigen::Isometry3d::Identity();
  turn.linear() = Eigen::AngleAxisd(M_PI / 2, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  ros_visualization::TrajectoryPaths paths;
  paths.AddKeyframe(0, ros::Time(10.0), At(0) * mount);
  paths.AddKeyframe(1, ros::Time(11.0), At(1) * mount);
  for (int i = 0; i < 20; ++i) paths.AddOdometry(ros::Time(10.0 + 0.1 * i), At(0.1 * i));
  MapGraph graph;
  graph.keyframe_ids = {0, 1};
  graph.keyframe_poses = {ros_conversions::ToPoseMessage(At(0) * mount),
                          ros_conversions::ToPoseMessage(turn * At(1) * mount)};
  graph.map_to_odom.rotation.w = 1;
  paths.SetGraph(graph);
  const nav_msgs::Path map_path = paths.MapPath("map", 100);
  ASSERT_EQ(map_path.poses.size(), 20u);
  EXPECT_TRUE(ros_conversions::FromPoseMessage(map_path.poses[5].pose).isApprox(At(0.5), 1e-9));
  EXPECT_TRUE(
      ros_conversions::FromPoseMessage(map_path.poses[15].pose).isApprox(turn * At(1.5), 1e-9));
}

// Frames tracked after keyframe 0 (at x = 0) and keyframe 1 (at x = 1 in odom); the graph then
// moves keyframe 1 sideways by 0.5 m (a loop closure): the frames after it follow, the ones
// before stay, and the odometry path does not change.
TEST(TrajectoryPaths, TheMapPathFollowsCorrectedKeyframes) {
  ros_visualization::TrajectoryPaths paths;
  paths.AddKeyframe(0, ros::Time(10.0), At(0));
  paths.AddKeyframe(1, ros::Time(11.0), At(1));
  for (int i = 0; i < 20; ++i) paths.AddOdometry(ros::Time(10.0 + 0.1 * i), At(0.1 * i));
  MapGraph graph;
  graph.keyframe_ids = {0, 1};
  graph.keyframe_poses = {ros_conversions::ToPoseMessage(At(0)),
                          ros_conversions::ToPoseMessage(At(1, 0.5))};
  graph.map_to_odom.rotation.w = 1;
  paths.SetGraph(graph);
  const nav_msgs::Path map_path = paths.MapPath("map", 100);
  ASSERT_EQ(map_path.poses.size(), 20u);
  EXPECT_NEAR(map_path.poses[5].pose.position.y, 0.0, 1e-12);
  EXPECT_NEAR(map_path.poses[15].pose.position.y, 0.5, 1e-12);
  EXPECT_NEAR(map_path.poses[15].pose.position.x, 1.5, 1e-12);
  EXPECT_NEAR(paths.OdometryPath("odom", 100).poses[15].pose.position.y, 0.0, 1e-12);
  // Thinned to at most 6, the newest kept.
  const nav_msgs::Path thinned = paths.OdometryPath("odom", 6);
  EXPECT_LE(thinned.poses.size(), 6u);
  EXPECT_GE(thinned.poses.size(), 5u);
  EXPECT_NEAR(thinned.poses.back().pose.position.x, 1.9, 1e-12);
  // A bag played again: the paths start over.
  paths.AddOdometry(ros::Time(10.0), At(0));
  EXPECT_EQ(paths.frames(), 1u);
}

TEST(MapCloud, EachMapPointOnceAtItsKeyframesMapPose) {
  stereo_fabmap_slam::Keyframe first, second;
  first.id = 0;
  second.id = 1;
  const auto point = [](float x, float y, float z) {
    geometry_msgs::Point p;
    p.x = x;
    p.y = y;
    p.z = z;
    return p;
  };
  first.points = {point(0, 0, 2), point(1, 0, 3), point(0, 0, 0)};
  first.map_point_ids = {7, -1, 8};  // an untracked point and one without depth: left out
  second.points = {point(0, 0, 2), point(0, 1, 4)};
  second.map_point_ids = {7, 9};  // 7 again: already in the cloud
  ros_visualization::MapCloud cloud;
  cloud.AddKeyframe(first);
  cloud.AddKeyframe(second);
  EXPECT_EQ(cloud.points(), 2u);
  MapGraph graph;
  graph.header.frame_id = "map";
  graph.keyframe_ids = {0, 1};
  graph.keyframe_poses = {ros_conversions::ToPoseMessage(At(10)),
                          ros_conversions::ToPoseMessage(At(20))};
  // Keyframe 1 turned by 90 degrees about z: its point (0, 1, 4) lands at (20 - 1, 0, 4).
  Eigen::Isometry3d turned = At(20);
  turned.linear() = Eigen::AngleAxisd(M_PI / 2, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  graph.keyframe_poses[1] = ros_conversions::ToPoseMessage(turned);
  const sensor_msgs::PointCloud2 message = cloud.Build(graph, 1000);
  ASSERT_EQ(message.width * message.height, 2u);
  sensor_msgs::PointCloud2ConstIterator<float> x(message, "x"), y(message, "y"), z(message, "z");
  EXPECT_FLOAT_EQ(*x, 10.0f);
  EXPECT_FLOAT_EQ(*z, 2.0f);
  ++x, ++y, ++z;
  EXPECT_NEAR(*x, 19.0f, 1e-5);
  EXPECT_NEAR(*y, 0.0f, 1e-5);
  EXPECT_NEAR(*z, 4.0f, 1e-5);
  EXPECT_EQ(cloud.Build(graph, 1).width * cloud.Build(graph, 1).height, 1u);  // bounded
  graph.keyframe_ids = {1};  // keyframe 0 not (yet) in the graph: its points wait
  graph.keyframe_poses = {ros_conversions::ToPoseMessage(At(20))};
  EXPECT_EQ(cloud.Build(graph, 1000).width, 1u);
  // Keyframe 0 sent again without point 7: 7 is free for another keyframe to bring.
  first.map_point_ids = {-1, -1, 8};
  cloud.AddKeyframe(first);
  EXPECT_EQ(cloud.points(), 1u);
  cloud.AddKeyframe(second);
  EXPECT_EQ(cloud.points(), 2u);
}

TEST(TrackingImage, ColoursSayWhatTrackingMadeOfEachPoint) {
  const cv::Mat gray(120, 160, CV_8UC1, cv::Scalar(128));
  odometry::TrackingResult result;
  result.state = odometry::TrackingState::kOk;
  result.inlier_pixels = {cv::Point2f(40, 60)};
  result.outlier_pixels = {cv::Point2f(80, 60)};
  result.untracked_pixels = {cv::Point2f(120, 60)};
  const sensor_msgs::ImagePtr message =
      ros_visualization::TrackingImageMessage(gray, result, ros::Time(3.0), "camera_optical");
  EXPECT_EQ(message->encoding, "bgr8");
  EXPECT_EQ(message->header.frame_id, "camera_optical");
  const cv::Mat image(120, 160, CV_8UC3, message->data.data(), message->step);
  // Each mark's colour appears around its point (a circle of radius 3, a cross, a circle of 2).
  const auto has_colour_near = [&](cv::Point centre, const cv::Scalar& colour) {
    for (int dy = -4; dy <= 4; ++dy) {
      for (int dx = -4; dx <= 4; ++dx) {
        const cv::Vec3b pixel = image.at<cv::Vec3b>(centre.y + dy, centre.x + dx);
        if (std::abs(pixel[0] - colour[0]) + std::abs(pixel[1] - colour[1]) +
                std::abs(pixel[2] - colour[2]) <
            60) {
          return true;
        }
      }
    }
    return false;
  };
  EXPECT_TRUE(has_colour_near({40, 60}, ros_visualization::kInlierColor));
  EXPECT_FALSE(has_colour_near({40, 60}, ros_visualization::kOutlierColor));
  EXPECT_TRUE(has_colour_near({80, 60}, ros_visualization::kOutlierColor));
  EXPECT_TRUE(has_colour_near({120, 60}, ros_visualization::kUntrackedColor));
}

// The topics the package's sources advertise (advertise<...>("name", ...) in src/).
std::set<std::string> AdvertisedTopics() {
  std::set<std::string> topics;
  const std::regex advertise(R"re(advertise<[^>]+>\(\s*"([a-z_]+)")re");
  for (const auto& entry :
       std::filesystem::recursive_directory_iterator(RepositoryRoot() + "/src")) {
    if (entry.path().extension() != ".cpp") continue;
    const std::string text = ReadTextFile(entry.path().string());
    for (std::sregex_iterator it(text.begin(), text.end(), advertise), end; it != end; ++it) {
      topics.insert((*it)[1]);
    }
  }
  return topics;
}

// The shipped rviz view (issue 34: a view fixed 19 m out made a small scene a dot): it follows
// the camera (orbit target base_link, the launch files' base frame) from at most 10 m, so that
// MH01's first 10 s, whose keyframes lie within about 4 m, fill it as a large route does; the
// fixed frame is the map; every display shows a topic the package publishes.
TEST(RvizConfig, TheShippedViewFollowsTheCameraAndShowsThePackagesTopics) {
  const YAML::Node root =
      YAML::LoadFile(RepositoryRoot() + "/config/stereo_fabmap_slam.rviz")["Visualization Manager"];
  ASSERT_TRUE(root.IsMap());
  EXPECT_EQ(root["Global Options"]["Fixed Frame"].as<std::string>(), "map");
  const YAML::Node view = root["Views"]["Current"];
  EXPECT_EQ(view["Class"].as<std::string>(), "rviz/Orbit");
  EXPECT_EQ(view["Target Frame"].as<std::string>(), "base_link");
  EXPECT_GT(view["Distance"].as<double>(), 0.0);
  EXPECT_LE(view["Distance"].as<double>(), 10.0);
  const std::set<std::string> advertised = AdvertisedTopics();
  ASSERT_GT(advertised.count("odometry"), 0u) << "the sources were read";
  int topics = 0;
  for (const YAML::Node& display : root["Displays"]) {
    for (const char* key : {"Topic", "Marker Topic", "Image Topic"}) {
      if (!display[key]) continue;
      const std::string topic = display[key].as<std::string>();
      ASSERT_FALSE(topic.empty());
      EXPECT_EQ(advertised.count(topic.substr(topic[0] == '/' ? 1 : 0)), 1u)
          << display["Name"].as<std::string>() << ": " << topic;
      ++topics;
    }
  }
  EXPECT_EQ(topics, 7) << "map cloud, markers, two paths, the tracking image, dense mesh and cloud";
}

}  // namespace
}  // namespace stereo_fabmap_slam::test
