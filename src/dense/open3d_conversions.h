#pragma once

// The dense module's meshes and clouds to and from Open3D's (legacy) geometry; private to the
// dense library, which alone sees Open3D.

#include <open3d/geometry/PointCloud.h>
#include <open3d/geometry/TriangleMesh.h>

#include "stereo_fabmap_slam/dense/depth_fusion.h"

namespace stereo_fabmap_slam::dense {

open3d::geometry::TriangleMesh ToOpen3d(const Mesh& mesh);
Mesh FromOpen3d(open3d::geometry::TriangleMesh mesh);
open3d::geometry::PointCloud ToOpen3d(const Cloud& cloud);
Cloud FromOpen3d(open3d::geometry::PointCloud cloud);

}  // namespace stereo_fabmap_slam::dense
