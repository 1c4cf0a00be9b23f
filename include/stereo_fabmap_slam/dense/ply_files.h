#pragma once

#include <string>

#include "stereo_fabmap_slam/dense/depth_fusion.h"

namespace stereo_fabmap_slam::dense {

// PLY files of the dense map (binary, as Open3D writes and reads them; MeshLab and CloudCompare
// open them too), grey levels as colours. Writers throw std::runtime_error when the file cannot
// be written; readers when it cannot be read.
void WriteMeshPly(const Mesh& mesh, const std::string& path);
void WriteCloudPly(const Cloud& cloud, const std::string& path);
Mesh ReadMeshPly(const std::string& path);
Cloud ReadCloudPly(const std::string& path);

}  // namespace stereo_fabmap_slam::dense
