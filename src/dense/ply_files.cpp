#include "stereo_fabmap_slam/dense/ply_files.h"

#include <stdexcept>

#include <open3d/geometry/PointCloud.h>
#include <open3d/geometry/TriangleMesh.h>
#include <open3d/io/PointCloudIO.h>
#include <open3d/io/TriangleMeshIO.h>

namespace stereo_fabmap_slam::dense {
namespace {

std::vector<Eigen::Vector3d> GreyToColours(const std::vector<float>& grey) {
  std::vector<Eigen::Vector3d> colours;
  colours.reserve(grey.size());
  for (const float g : grey) colours.push_back(Eigen::Vector3d::Constant(g));
  return colours;
}

std::vector<float> ColoursToGrey(const std::vector<Eigen::Vector3d>& colours) {
  std::vector<float> grey;
  grey.reserve(colours.size());
  for (const Eigen::Vector3d& colour : colours) grey.push_back(static_cast<float>(colour.mean()));
  return grey;
}

}  // namespace

void WriteMeshPly(const Mesh& mesh, const std::string& path) {
  open3d::geometry::TriangleMesh converted;
  converted.vertices_ = mesh.vertices;
  converted.triangles_ = mesh.triangles;
  converted.vertex_colors_ = GreyToColours(mesh.grey);
  if (!open3d::io::WriteTriangleMesh(path, converted))
    throw std::runtime_error("cannot write the mesh " + path);
}

void WriteCloudPly(const Cloud& cloud, const std::string& path) {
  open3d::geometry::PointCloud converted;
  converted.points_ = cloud.points;
  converted.normals_ = cloud.normals;
  converted.colors_ = GreyToColours(cloud.grey);
  if (!open3d::io::WritePointCloud(path, converted))
    throw std::runtime_error("cannot write the cloud " + path);
}

Mesh ReadMeshPly(const std::string& path) {
  open3d::geometry::TriangleMesh read;
  if (!open3d::io::ReadTriangleMesh(path, read)) throw std::runtime_error("cannot read " + path);
  Mesh mesh;
  mesh.vertices = std::move(read.vertices_);
  mesh.triangles = std::move(read.triangles_);
  mesh.grey = ColoursToGrey(read.vertex_colors_);
  return mesh;
}

Cloud ReadCloudPly(const std::string& path) {
  open3d::geometry::PointCloud read;
  if (!open3d::io::ReadPointCloud(path, read)) throw std::runtime_error("cannot read " + path);
  Cloud cloud;
  cloud.points = std::move(read.points_);
  cloud.normals = std::move(read.normals_);
  cloud.grey = ColoursToGrey(read.colors_);
  return cloud;
}

}  // namespace stereo_fabmap_slam::dense
