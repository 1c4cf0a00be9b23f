#include "stereo_fabmap_slam/dense/surface_comparison.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include <open3d/geometry/KDTreeFlann.h>
#include <open3d/geometry/PointCloud.h>

namespace stereo_fabmap_slam::dense {

std::vector<double> NearestDistances(const std::vector<Eigen::Vector3d>& points,
                                     const std::vector<Eigen::Vector3d>& reference) {
  std::vector<double> distances(points.size(), std::numeric_limits<double>::infinity());
  if (reference.empty()) return distances;
  const open3d::geometry::PointCloud cloud(reference);
  const open3d::geometry::KDTreeFlann tree(cloud);
  std::vector<int> index(1);
  std::vector<double> squared(1);
  for (std::size_t i = 0; i < points.size(); ++i) {
    if (tree.SearchKNN(points[i], 1, index, squared) > 0) distances[i] = std::sqrt(squared[0]);
  }
  return distances;
}

double Completeness(const std::vector<Eigen::Vector3d>& reconstruction,
                    const std::vector<Eigen::Vector3d>& reference, double radius) {
  if (reference.empty()) return 0.0;
  const std::vector<double> distances = NearestDistances(reference, reconstruction);
  const auto covered = std::count_if(distances.begin(), distances.end(),
                                     [radius](double distance) { return distance <= radius; });
  return static_cast<double>(covered) / static_cast<double>(reference.size());
}

double SurfaceArea(const std::vector<Eigen::Vector3d>& vertices,
                   const std::vector<Eigen::Vector3i>& triangles) {
  double area = 0.0;
  for (const Eigen::Vector3i& triangle : triangles) {
    const Eigen::Vector3d& a = vertices[static_cast<std::size_t>(triangle[0])];
    area += 0.5 * (vertices[static_cast<std::size_t>(triangle[1])] - a)
                      .cross(vertices[static_cast<std::size_t>(triangle[2])] - a)
                      .norm();
  }
  return area;
}

double Quantile(std::vector<double> values, double q) {
  if (values.empty()) return 0.0;
  const auto k = static_cast<std::ptrdiff_t>(
      std::clamp(q, 0.0, 1.0) * static_cast<double>(values.size() - 1) + 0.5);
  std::nth_element(values.begin(), values.begin() + k, values.end());
  return values[static_cast<std::size_t>(k)];
}

}  // namespace stereo_fabmap_slam::dense
