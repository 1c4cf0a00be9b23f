#pragma once

#include <optional>
#include <string>
#include <vector>

#include <Eigen/Geometry>

namespace stereo_fabmap_slam::evaluation {

enum class AlignmentMode { kNone, kSE3, kSim3 };

// "none", "se3", "sim3" (case-sensitive); nullopt for anything else.
std::optional<AlignmentMode> ParseAlignmentMode(const std::string& name);
const char* AlignmentModeName(AlignmentMode mode);

// x -> scale * rotation * x + translation.
struct Similarity3 {
  Eigen::Matrix3d rotation = Eigen::Matrix3d::Identity();
  Eigen::Vector3d translation = Eigen::Vector3d::Zero();
  double scale = 1.0;

  Eigen::Vector3d operator*(const Eigen::Vector3d& point) const {
    return scale * (rotation * point) + translation;
  }
  // A pose moved by this transform: its position is mapped, its orientation rotated.
  Eigen::Isometry3d Apply(const Eigen::Isometry3d& pose) const;
};

// The transform that best maps `estimate` onto `reference` (corresponding points, least squares,
// Umeyama 1991, through Eigen::umeyama). SE(3) needs 3 points, Sim(3) 3 points not all on a line;
// throws std::invalid_argument if there are too few. kNone gives the identity.
Similarity3 AlignPositions(const std::vector<Eigen::Vector3d>& reference,
                           const std::vector<Eigen::Vector3d>& estimate, AlignmentMode mode);

}  // namespace stereo_fabmap_slam::evaluation
