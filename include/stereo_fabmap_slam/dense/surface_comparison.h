#pragma once

#include <cstddef>
#include <vector>

#include <Eigen/Core>

namespace stereo_fabmap_slam::dense {

// Distance [m] from each of `points` to the nearest of `reference` (Open3D's k-d tree); all
// infinite if `reference` is empty.
std::vector<double> NearestDistances(const std::vector<Eigen::Vector3d>& points,
                                     const std::vector<Eigen::Vector3d>& reference);

// Fraction of `reference` with a point of `reconstruction` within `radius` [m]: how much of a
// surface a reconstruction covers (0 if `reference` is empty).
double Completeness(const std::vector<Eigen::Vector3d>& reconstruction,
                    const std::vector<Eigen::Vector3d>& reference, double radius);

// The summed area of a mesh's triangles [m^2]: the surface a volume holds, to state its memory
// per square metre.
double SurfaceArea(const std::vector<Eigen::Vector3d>& vertices,
                   const std::vector<Eigen::Vector3i>& triangles);

// The value below which fraction `q` (0-1) of `values` lie (nearest rank); 0 if empty.
double Quantile(std::vector<double> values, double q);

}  // namespace stereo_fabmap_slam::dense
