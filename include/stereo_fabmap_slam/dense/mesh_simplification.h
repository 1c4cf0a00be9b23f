#pragma once

#include "stereo_fabmap_slam/dense/depth_fusion.h"

namespace stereo_fabmap_slam::dense {

// The mesh with its vertices merged per cube of `cell` [m] (Open3D's vertex clustering, grey
// levels averaged): the same surface in far fewer triangles, for a viewer. Every k-th triangle
// would keep the count down too, but leaves scattered specks where a surface was.
Mesh SimplifiedMesh(const Mesh& mesh, double cell);

}  // namespace stereo_fabmap_slam::dense
