#include "stereo_fabmap_slam/dense/ply_files.h"

#include <stdexcept>
#include <utility>

#include <open3d/io/PointCloudIO.h>
#include <open3d/io/TriangleMeshIO.h>

#include "open3d_conversions.h"

namespace stereo_fabmap_slam::dense {

void WriteMeshPly(const Mesh& mesh, const std::string& path) {
  if (!open3d::io::WriteTriangleMesh(path, ToOpen3d(mesh)))
    throw std::runtime_error("cannot write the mesh " + path);
}

void WriteCloudPly(const Cloud& cloud, const std::string& path) {
  if (!open3d::io::WritePointCloud(path, ToOpen3d(cloud)))
    throw std::runtime_error("cannot write the cloud " + path);
}

Mesh ReadMeshPly(const std::string& path) {
  open3d::geometry::TriangleMesh read;
  if (!open3d::io::ReadTriangleMesh(path, read)) throw std::runtime_error("cannot read " + path);
  return FromOpen3d(std::move(read));
}

Cloud ReadCloudPly(const std::string& path) {
  open3d::geometry::PointCloud read;
  if (!open3d::io::ReadPointCloud(path, read)) throw std::runtime_error("cannot read " + path);
  return FromOpen3d(std::move(read));
}

}  // namespace stereo_fabmap_slam::dense
