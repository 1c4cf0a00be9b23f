#pragma once

#include <string>

#include "stereo_fabmap_slam/datasets/euroc_sequence.h"

namespace stereo_fabmap_slam::ros_conversions {

// Writes an EuRoC sequence into a bag, in time order as a recorder would: /cam0/image_raw and
// /cam1/image_raw (mono8, stamp = image time, frame ids cam0 and cam1), /cam0/camera_info and
// /cam1/camera_info (the calibration's rectification: K, D, R, P) and, if the sequence has
// ground truth, /ground_truth (geometry_msgs/PoseStamped, body frame in "world").
void WriteEurocBag(const datasets::EurocSequence& sequence, const std::string& bag_path);

}  // namespace stereo_fabmap_slam::ros_conversions
