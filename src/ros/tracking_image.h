#pragma once

// The front end's view of a frame, as other SLAM front ends publish it for debugging: the
// rectified left image with its key points coloured by what tracking made of them.

#include <string>

#include <ros/time.h>
#include <sensor_msgs/Image.h>
#include <opencv2/core.hpp>

#include "stereo_fabmap_slam/odometry/tracker.h"

namespace stereo_fabmap_slam::ros_visualization {

// Colours (BGR): tracked inliers green, outliers red, untracked stereo points (new points of a
// keyframe) blue; a keyframe gets a yellow frame. A line of text says the state and counts.
inline const cv::Scalar kInlierColor(40, 200, 40);
inline const cv::Scalar kOutlierColor(40, 40, 230);
inline const cv::Scalar kUntrackedColor(230, 120, 30);

cv::Mat DrawTracking(const cv::Mat& rectified_left, const odometry::TrackingResult& result);

// DrawTracking as a bgr8 image message.
sensor_msgs::ImagePtr TrackingImageMessage(const cv::Mat& rectified_left,
                                           const odometry::TrackingResult& result,
                                           const ros::Time& stamp, const std::string& frame_id);

}  // namespace stereo_fabmap_slam::ros_visualization
