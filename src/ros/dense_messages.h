#pragma once

// The DenseMapper's messages for rviz: the dense cloud, thinned to one point a cell, as a
// PointCloud2 (x, y, z, intensity), and the mesh as a triangle-list marker coloured by grey level.

#include <cstddef>
#include <string>

#include <ros/time.h>
#include <sensor_msgs/PointCloud2.h>
#include <visualization_msgs/Marker.h>

#include "stereo_fabmap_slam/dense/depth_fusion.h"

namespace stereo_fabmap_slam::ros_visualization {

// One point (the first) of every cube of `cell` [m] the cloud has points in; intensity is the
// grey level (0-1).
sensor_msgs::PointCloud2 DenseCloudMessage(const dense::Cloud& cloud, double cell,
                                           const std::string& frame, const ros::Time& stamp);
// At most `max_triangles` triangles (every k-th beyond that; the DenseMapper simplifies the mesh
// to fit first, dense::SimplifiedMesh, since scattered triangles show no surface).
visualization_msgs::Marker DenseMeshMarker(const dense::Mesh& mesh, std::size_t max_triangles,
                                           const std::string& frame, const ros::Time& stamp);

}  // namespace stereo_fabmap_slam::ros_visualization
