#include "stereo_fabmap_slam/dense/view_facing_surface.h"

#include <cstdint>
#include <utility>

#include <opencv2/core/utility.hpp>

namespace stereo_fabmap_slam::dense {

ViewFacingSurface::ViewFacingSurface(std::vector<Eigen::Isometry3d> views,
                                     const geometry::StereoCamera& camera, double max_depth)
    : camera_(camera), max_depth_(max_depth) {
  for (const Eigen::Isometry3d& T_world_camera : views) {
    T_camera_world_.push_back(T_world_camera.inverse());
    centres_.push_back(T_world_camera.translation());
  }
}

bool ViewFacingSurface::Sees(std::size_t view, const Eigen::Vector3d& point,
                             const Eigen::Vector3d& normal) const {
  if (normal.dot(centres_[view] - point) <= 0.0) return false;  // from behind, or edge on
  const Eigen::Vector3d p = T_camera_world_[view] * point;
  if (!(p.z() > 0.0) || p.z() > max_depth_) return false;
  const double u = camera_.fx * p.x() / p.z() + camera_.cx;
  const double v = camera_.fy * p.y() / p.z() + camera_.cy;
  return u >= -0.5 && v >= -0.5 && u < camera_.size.width - 0.5 && v < camera_.size.height - 0.5;
}

bool ViewFacingSurface::Faces(const Eigen::Vector3d& point, const Eigen::Vector3d& normal,
                              std::size_t* hint) const {
  const std::size_t views = centres_.size();
  if (views == 0) return false;
  const std::size_t first = *hint < views ? *hint : 0;
  for (std::size_t k = 0; k < views; ++k) {
    const std::size_t view = (first + k) % views;
    if (Sees(view, point, normal)) {
      *hint = view;
      return true;
    }
  }
  return false;
}

namespace {

// `keep(i)` for i in [0, count), in parallel; each band of indices keeps its own hint.
template <typename Test>
std::vector<std::uint8_t> KeptFlags(std::size_t count, Test keep) {
  std::vector<std::uint8_t> kept(count, 0);
  cv::parallel_for_(cv::Range(0, static_cast<int>(count)), [&](const cv::Range& range) {
    std::size_t hint = 0;
    for (int i = range.start; i < range.end; ++i)
      kept[static_cast<std::size_t>(i)] = keep(static_cast<std::size_t>(i), &hint) ? 1 : 0;
  });
  return kept;
}

}  // namespace

Mesh ViewFacingSurface::Keep(const Mesh& mesh) const {
  // Marching cubes winds each triangle counter-clockwise seen from the + side (free space):
  // (b - a) x (c - a) points to the cameras that measured the surface.
  const std::vector<std::uint8_t> kept =
      KeptFlags(mesh.triangles.size(), [&](std::size_t i, std::size_t* hint) {
        const Eigen::Vector3i& t = mesh.triangles[i];
        const Eigen::Vector3d& a = mesh.vertices[static_cast<std::size_t>(t.x())];
        const Eigen::Vector3d& b = mesh.vertices[static_cast<std::size_t>(t.y())];
        const Eigen::Vector3d& c = mesh.vertices[static_cast<std::size_t>(t.z())];
        return Faces((a + b + c) / 3.0, (b - a).cross(c - a), hint);
      });
  Mesh result;
  std::vector<int> index(mesh.vertices.size(), -1);
  const auto Index = [&](int vertex) {
    int& slot = index[static_cast<std::size_t>(vertex)];
    if (slot < 0) {
      slot = static_cast<int>(result.vertices.size());
      result.vertices.push_back(mesh.vertices[static_cast<std::size_t>(vertex)]);
      if (static_cast<std::size_t>(vertex) < mesh.grey.size())
        result.grey.push_back(mesh.grey[static_cast<std::size_t>(vertex)]);
    }
    return slot;
  };
  for (std::size_t i = 0; i < mesh.triangles.size(); ++i) {
    if (!kept[i]) continue;
    const Eigen::Vector3i& t = mesh.triangles[i];
    const int a = Index(t.x()), b = Index(t.y()), c = Index(t.z());
    result.triangles.emplace_back(a, b, c);
  }
  return result;
}

Cloud ViewFacingSurface::Keep(const Cloud& cloud) const {
  if (cloud.normals.size() != cloud.points.size()) return cloud;
  // The cloud's normals are the signed distance's gradient: towards free space.
  const std::vector<std::uint8_t> kept =
      KeptFlags(cloud.points.size(), [&](std::size_t i, std::size_t* hint) {
        return Faces(cloud.points[i], cloud.normals[i], hint);
      });
  Cloud result;
  for (std::size_t i = 0; i < cloud.points.size(); ++i) {
    if (!kept[i]) continue;
    result.points.push_back(cloud.points[i]);
    result.normals.push_back(cloud.normals[i]);
    if (i < cloud.grey.size()) result.grey.push_back(cloud.grey[i]);
  }
  return result;
}

}  // namespace stereo_fabmap_slam::dense
