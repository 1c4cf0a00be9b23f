#include "stereo_fabmap_slam/datasets/rounded_path.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace stereo_fabmap_slam::datasets {
namespace {

double Cross(const Eigen::Vector2d& a, const Eigen::Vector2d& b) {
  return a.x() * b.y() - a.y() * b.x();
}

Eigen::Vector2d Rotate(const Eigen::Vector2d& v, double angle) {
  const double c = std::cos(angle), s = std::sin(angle);
  return {c * v.x() - s * v.y(), s * v.x() + c * v.y()};
}

}  // namespace

RoundedPath::RoundedPath(std::vector<Eigen::Vector2d> waypoints, double corner_radius)
    : radius_(corner_radius) {
  const std::size_t n = waypoints.size();
  if (n < 3) throw std::invalid_argument("a closed path needs at least three waypoints");
  if (!(corner_radius > 0)) throw std::invalid_argument("the corner radius must be > 0");
  // Per corner: the turn and how far before and after the waypoint its arc starts and ends.
  std::vector<double> turns(n), cut(n);
  std::vector<Eigen::Vector2d> legs(n);  // legs[i]: waypoint i to i + 1
  for (std::size_t i = 0; i < n; ++i) {
    legs[i] = waypoints[(i + 1) % n] - waypoints[i];
    if (legs[i].norm() < 1e-9) throw std::invalid_argument("two consecutive waypoints are equal");
  }
  for (std::size_t i = 0; i < n; ++i) {
    const Eigen::Vector2d in = legs[(i + n - 1) % n].normalized(), out = legs[i].normalized();
    turns[i] = std::atan2(Cross(in, out), in.dot(out));
    cut[i] = corner_radius * std::tan(0.5 * std::abs(turns[i]));
  }
  for (std::size_t i = 0; i < n; ++i) {
    const double leg = legs[i].norm();
    const double straight = leg - cut[i] - cut[(i + 1) % n];
    if (straight < -1e-9) {
      throw std::invalid_argument("a leg is too short for the corner radius at its ends");
    }
    const Eigen::Vector2d direction = legs[i] / leg;
    // The arc of corner i, then the straight part of leg i.
    if (std::abs(turns[i]) > 1e-9) {
      const Eigen::Vector2d in = legs[(i + n - 1) % n].normalized();
      const Eigen::Vector2d arc_start = waypoints[i] - cut[i] * in;
      const Eigen::Vector2d left(-in.y(), in.x());
      Piece arc;
      arc.start = length_;
      arc.length = corner_radius * std::abs(turns[i]);
      arc.from = arc_start;
      arc.direction = in;
      arc.centre = arc_start + (turns[i] > 0 ? 1.0 : -1.0) * corner_radius * left;
      arc.turn = turns[i];
      pieces_.push_back(arc);
      length_ += arc.length;
    }
    Piece straight_piece;
    straight_piece.start = length_;
    straight_piece.length = std::max(0.0, straight);
    straight_piece.from = waypoints[i] + cut[i] * direction;
    straight_piece.direction = direction;
    pieces_.push_back(straight_piece);
    length_ += straight_piece.length;
  }
}

const RoundedPath::Piece& RoundedPath::PieceAt(double* distance) const {
  double s = std::fmod(*distance, length_);
  if (s < 0) s += length_;
  const auto after = std::upper_bound(pieces_.begin(), pieces_.end(), s,
                                      [](double value, const Piece& p) { return value < p.start; });
  const Piece& piece = *(after == pieces_.begin() ? after : after - 1);
  *distance = std::min(s - piece.start, piece.length);
  return piece;
}

Eigen::Vector2d RoundedPath::Position(double distance) const {
  const Piece& piece = PieceAt(&distance);
  if (piece.turn == 0) return piece.from + distance * piece.direction;
  const double angle = (piece.turn > 0 ? 1.0 : -1.0) * distance / radius_;
  return piece.centre + Rotate(piece.from - piece.centre, angle);
}

Eigen::Vector2d RoundedPath::Direction(double distance) const {
  const Piece& piece = PieceAt(&distance);
  if (piece.turn == 0) return piece.direction;
  return Rotate(piece.direction, (piece.turn > 0 ? 1.0 : -1.0) * distance / radius_);
}

}  // namespace stereo_fabmap_slam::datasets
