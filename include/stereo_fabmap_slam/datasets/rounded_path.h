#pragma once

#include <vector>

#include <Eigen/Core>

namespace stereo_fabmap_slam::datasets {

// A closed walk on the floor plan: straight legs between waypoints, every corner rounded by a
// circular arc of one radius, as a person walking a corridor cuts a corner. Parameterised by the
// distance walked, which wraps around the closed path.
class RoundedPath {
 public:
  // Throws std::invalid_argument for fewer than three waypoints, two equal consecutive ones, a
  // radius <= 0, or a leg too short for the arcs at its two ends.
  RoundedPath(std::vector<Eigen::Vector2d> waypoints, double corner_radius);

  double length() const { return length_; }
  Eigen::Vector2d Position(double distance) const;
  Eigen::Vector2d Direction(double distance) const;  // unit tangent

 private:
  struct Piece {
    double start = 0, length = 0;  // along the path
    // A leg: from + s * direction. An arc: from its start `from` (entered along `direction`),
    // turning about `centre`, counter-clockwise if turn > 0.
    Eigen::Vector2d from = Eigen::Vector2d::Zero(), direction = Eigen::Vector2d::UnitX();
    Eigen::Vector2d centre = Eigen::Vector2d::Zero();
    double turn = 0;  // [rad] signed; 0 for a leg
  };
  const Piece& PieceAt(double* distance) const;  // wraps *distance into [0, length), local to it

  std::vector<Piece> pieces_;
  double radius_;
  double length_ = 0;
};

}  // namespace stereo_fabmap_slam::datasets
