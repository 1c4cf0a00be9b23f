#pragma once

// A world of 3-D points with distinct binary descriptors, and what a rectified stereo camera at a
// given pose would extract from it: for tests of tracking and loop verification without images.

#include <random>
#include <vector>

#include <Eigen/Geometry>
#include <opencv2/core.hpp>

#include "stereo_fabmap_slam/features/stereo_features.h"
#include "stereo_fabmap_slam/geometry/stereo_camera.h"

namespace stereo_fabmap_slam::test {

inline const geometry::StereoCamera kTestCamera{
    cv::Size(752, 480), 458.0, 458.0, 376.0, 240.0, 0.11};

// 64-byte random descriptors are ~256 bits apart, far beyond any match limit: every match is
// the true one, unless a test gives two points the same descriptor on purpose.
struct StereoWorld {
  std::vector<Eigen::Vector3d> points;
  cv::Mat descriptors;  // one row per point, CV_8U, 64 bytes

  // Adds points with new random descriptors; returns the index of the first.
  int Add(const std::vector<Eigen::Vector3d>& new_points, std::uint64_t seed) {
    cv::Mat rows(static_cast<int>(new_points.size()), 64, CV_8U);
    cv::RNG rng(seed);
    rng.fill(rows, cv::RNG::UNIFORM, 0, 256);
    return Add(new_points, rows);
  }
  // Adds points with the given descriptors (e.g. a copy of other points' to repeat an object).
  int Add(const std::vector<Eigen::Vector3d>& new_points, const cv::Mat& rows) {
    const int first = static_cast<int>(points.size());
    points.insert(points.end(), new_points.begin(), new_points.end());
    if (descriptors.empty()) {
      descriptors = rows.clone();
    } else {
      cv::vconcat(descriptors, rows, descriptors);
    }
    return first;
  }
};

// `count` points in front of a camera at the origin, spread over its whole image (x, y lateral,
// z depth between near and far) [m].
inline std::vector<Eigen::Vector3d> RandomPoints(int count, std::uint64_t seed,
                                                 double half_width = 6.4, double near = 3.0,
                                                 double far = 8.0) {
  std::mt19937 random(static_cast<unsigned>(seed));
  std::uniform_real_distribution<double> lateral(-half_width, half_width), depth(near, far);
  std::vector<Eigen::Vector3d> points;
  for (int i = 0; i < count; ++i) {
    const double z = depth(random);
    points.emplace_back(lateral(random) * z / far, 0.6 * lateral(random) * z / far, z);
  }
  return points;
}

// What the stereo extractor would find in a frame taken at T_world_camera: every point visible
// in both images, with its stereo match and triangulated point.
inline features::StereoFeatures Observe(const StereoWorld& world,
                                        const Eigen::Isometry3d& T_world_camera) {
  features::StereoFeatures features;
  std::vector<int> rows;
  const geometry::StereoCamera& camera = kTestCamera;
  for (int i = 0; i < static_cast<int>(world.points.size()); ++i) {
    const Eigen::Vector3d c = T_world_camera.inverse() * world.points[i];
    if (c.z() < 0.5) continue;
    const Eigen::Vector3d uvr = camera.Project(c);
    if (uvr.x() < 0 || uvr.y() < 0 || uvr.x() >= camera.size.width ||
        uvr.y() >= camera.size.height || uvr.z() < 0) {
      continue;
    }
    features.keypoints.emplace_back(static_cast<float>(uvr.x()), static_cast<float>(uvr.y()), 7.f);
    features.u_right.push_back(static_cast<float>(uvr.z()));
    features.points.push_back(c);
    rows.push_back(i);
  }
  features.descriptors = cv::Mat(static_cast<int>(rows.size()), 64, CV_8U);
  for (std::size_t k = 0; k < rows.size(); ++k) {
    world.descriptors.row(rows[k]).copyTo(features.descriptors.row(static_cast<int>(k)));
  }
  return features;
}

}  // namespace stereo_fabmap_slam::test
