#include "euroc_bag_writer.h"

#include <geometry_msgs/PoseStamped.h>
#include <rosbag/bag.h>

#include "ros_conversions.h"
#include "stereo_fabmap_slam/camera/stereo_rectifier.h"

namespace stereo_fabmap_slam::ros_conversions {
namespace {

void WriteGroundTruth(const io::StampedPose& body, rosbag::Bag* bag) {
  geometry_msgs::PoseStamped message;
  message.header.stamp.fromSec(body.timestamp);
  message.header.frame_id = "world";
  message.pose = ToPoseMessage(body.pose);
  bag->write("/ground_truth", message.header.stamp, message);
}

}  // namespace

void WriteEurocBag(const datasets::EurocSequence& sequence, const std::string& bag_path) {
  rosbag::Bag bag(bag_path, rosbag::bagmode::Write);
  const io::Trajectory& truth = sequence.ground_truth();
  std::size_t next_truth = 0;
  // camera_info with the rectification of the sequence's calibration (default options), so
  // that use_camera_info works on the bag as on a driver's output.
  const camera::StereoRectifier rectifier = camera::StereoRectifier::FromCalibration(
      sequence.calibration(), camera::RectificationOptions());
  sensor_msgs::CameraInfo left_info = ToCameraInfo(rectifier.left_parameters(), "cam0");
  sensor_msgs::CameraInfo right_info = ToCameraInfo(rectifier.right_parameters(), "cam1");
  for (std::size_t i = 0; i < sequence.size(); ++i) {
    const datasets::StereoImages images = sequence.LoadStereoPair(i);
    const ros::Time stamp = ToRosTime(images.timestamp_ns);
    for (; next_truth < truth.size() && truth[next_truth].timestamp <= stamp.toSec();
         ++next_truth) {
      WriteGroundTruth(truth[next_truth], &bag);
    }
    bag.write("/cam0/image_raw", stamp, ToMono8ImageMessage(images.left, stamp, "cam0"));
    bag.write("/cam1/image_raw", stamp, ToMono8ImageMessage(images.right, stamp, "cam1"));
    left_info.header.stamp = right_info.header.stamp = stamp;
    bag.write("/cam0/camera_info", stamp, left_info);
    bag.write("/cam1/camera_info", stamp, right_info);
  }
  for (; next_truth < truth.size(); ++next_truth) WriteGroundTruth(truth[next_truth], &bag);
  bag.close();
}

}  // namespace stereo_fabmap_slam::ros_conversions
