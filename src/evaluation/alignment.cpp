#include "stereo_fabmap_slam/evaluation/alignment.h"

#include <cmath>
#include <stdexcept>

#include <Eigen/Geometry>

namespace stereo_fabmap_slam::evaluation {

std::optional<AlignmentMode> ParseAlignmentMode(const std::string& name) {
  if (name == "none") return AlignmentMode::kNone;
  if (name == "se3") return AlignmentMode::kSE3;
  if (name == "sim3") return AlignmentMode::kSim3;
  return std::nullopt;
}

const char* AlignmentModeName(AlignmentMode mode) {
  switch (mode) {
    case AlignmentMode::kNone:
      return "none";
    case AlignmentMode::kSE3:
      return "se3";
    case AlignmentMode::kSim3:
      return "sim3";
  }
  return "?";
}

Eigen::Isometry3d Similarity3::Apply(const Eigen::Isometry3d& pose) const {
  Eigen::Isometry3d moved = Eigen::Isometry3d::Identity();
  moved.linear() = rotation * pose.linear();
  moved.translation() = *this * pose.translation();
  return moved;
}

Similarity3 AlignPositions(const std::vector<Eigen::Vector3d>& reference,
                           const std::vector<Eigen::Vector3d>& estimate, AlignmentMode mode) {
  if (reference.size() != estimate.size()) {
    throw std::invalid_argument(
        "alignment needs the same number of reference and estimated points");
  }
  Similarity3 result;
  if (mode == AlignmentMode::kNone) return result;
  if (reference.size() < 3) {
    throw std::invalid_argument("alignment needs at least 3 matched poses, got " +
                                std::to_string(reference.size()));
  }
  Eigen::Matrix3Xd source(3, estimate.size()), target(3, reference.size());
  for (std::size_t i = 0; i < reference.size(); ++i) {
    source.col(static_cast<Eigen::Index>(i)) = estimate[i];
    target.col(static_cast<Eigen::Index>(i)) = reference[i];
  }
  const Eigen::Matrix4d transform = Eigen::umeyama(source, target, mode == AlignmentMode::kSim3);
  // The top-left block is scale * rotation, so its determinant is scale^3.
  const double determinant = transform.topLeftCorner<3, 3>().determinant();
  if (!(determinant > 0) || !std::isfinite(determinant)) {
    throw std::invalid_argument("alignment is degenerate (estimated points collapse)");
  }
  result.scale = std::cbrt(determinant);
  result.rotation = transform.topLeftCorner<3, 3>() / result.scale;
  result.translation = transform.topRightCorner<3, 1>();
  return result;
}

}  // namespace stereo_fabmap_slam::evaluation
