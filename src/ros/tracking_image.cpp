#include "tracking_image.h"

#include <cv_bridge/cv_bridge.h>
#include <sensor_msgs/image_encodings.h>
#include <opencv2/imgproc.hpp>

namespace stereo_fabmap_slam::ros_visualization {
namespace {

const char* StateName(odometry::TrackingState state) {
  switch (state) {
    case odometry::TrackingState::kOk:
      return "OK";
    case odometry::TrackingState::kWeak:
      return "WEAK";
    default:
      return "LOST";
  }
}

}  // namespace

cv::Mat DrawTracking(const cv::Mat& rectified_left, const odometry::TrackingResult& result) {
  cv::Mat image;
  if (rectified_left.channels() == 1) {
    cv::cvtColor(rectified_left, image, cv::COLOR_GRAY2BGR);
  } else {
    image = rectified_left.clone();
  }
  // Untracked first: the tracked points are what a user looks for, drawn on top.
  for (const cv::Point2f& p : result.untracked_pixels) {
    cv::circle(image, p, 2, kUntrackedColor, 1, cv::LINE_AA);
  }
  for (const cv::Point2f& p : result.outlier_pixels) {
    cv::drawMarker(image, p, kOutlierColor, cv::MARKER_TILTED_CROSS, 6, 1, cv::LINE_AA);
  }
  for (const cv::Point2f& p : result.inlier_pixels) {
    cv::circle(image, p, 3, kInlierColor, 1, cv::LINE_AA);
  }
  if (result.keyframe) {
    cv::rectangle(image, cv::Rect(0, 0, image.cols, image.rows), cv::Scalar(0, 220, 255), 4);
  }
  const std::string text = std::string(StateName(result.state)) + "  tracked " +
                           std::to_string(result.inlier_pixels.size()) + "  outliers " +
                           std::to_string(result.outlier_pixels.size()) + "  untracked " +
                           std::to_string(result.untracked_pixels.size()) +
                           (result.keyframe ? "  KEYFRAME" : "");
  cv::rectangle(image, cv::Rect(0, 0, image.cols, 22), cv::Scalar(0, 0, 0), cv::FILLED);
  cv::putText(image, text, cv::Point(6, 16), cv::FONT_HERSHEY_SIMPLEX, 0.5,
              cv::Scalar(255, 255, 255), 1, cv::LINE_AA);
  return image;
}

sensor_msgs::ImagePtr TrackingImageMessage(const cv::Mat& rectified_left,
                                           const odometry::TrackingResult& result,
                                           const ros::Time& stamp, const std::string& frame_id) {
  std_msgs::Header header;
  header.stamp = stamp;
  header.frame_id = frame_id;
  return cv_bridge::CvImage(header, sensor_msgs::image_encodings::BGR8,
                            DrawTracking(rectified_left, result))
      .toImageMsg();
}

}  // namespace stereo_fabmap_slam::ros_visualization
