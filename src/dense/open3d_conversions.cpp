#include "open3d_conversions.h"

#include <utility>

namespace stereo_fabmap_slam::dense {
namespace {

// Grey levels (0-1) as Open3D's RGB colours, and back (their mean).
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

open3d::geometry::TriangleMesh ToOpen3d(const Mesh& mesh) {
  open3d::geometry::TriangleMesh converted;
  converted.vertices_ = mesh.vertices;
  converted.triangles_ = mesh.triangles;
  converted.vertex_colors_ = GreyToColours(mesh.grey);
  return converted;
}

Mesh FromOpen3d(open3d::geometry::TriangleMesh mesh) {
  Mesh converted;
  converted.vertices = std::move(mesh.vertices_);
  converted.triangles = std::move(mesh.triangles_);
  converted.grey = ColoursToGrey(mesh.vertex_colors_);
  return converted;
}

open3d::geometry::PointCloud ToOpen3d(const Cloud& cloud) {
  open3d::geometry::PointCloud converted;
  converted.points_ = cloud.points;
  converted.normals_ = cloud.normals;
  converted.colors_ = GreyToColours(cloud.grey);
  return converted;
}

Cloud FromOpen3d(open3d::geometry::PointCloud cloud) {
  Cloud converted;
  converted.points = std::move(cloud.points_);
  converted.normals = std::move(cloud.normals_);
  converted.grey = ColoursToGrey(cloud.colors_);
  return converted;
}

}  // namespace stereo_fabmap_slam::dense
