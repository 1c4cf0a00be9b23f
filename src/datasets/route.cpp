#include "stereo_fabmap_slam/datasets/route.h"

#include <cmath>
#include <utility>

namespace stereo_fabmap_slam::datasets {
namespace {
constexpr double kWalkingSpeed = 1.0;  // [m/s] along an office path
}  // namespace

std::optional<RouteKind> ParseRouteKind(const std::string& name) {
  if (name == "loop") return RouteKind::kLoop;
  if (name == "figure8") return RouteKind::kFigure8;
  if (name == "kidnap") return RouteKind::kKidnap;
  return std::nullopt;
}

const char* RouteKindName(RouteKind kind) {
  switch (kind) {
    case RouteKind::kLoop:
      return "loop";
    case RouteKind::kFigure8:
      return "figure8";
    case RouteKind::kKidnap:
      return "kidnap";
  }
  return "?";
}

Route::Route(RouteKind kind, const HallOptions& hall)
    : kind_(kind),
      centre_(0.5 * hall.length, 0.5 * hall.width),
      semi_x_(0.75 * hall.clear_semi_axis_x),
      semi_y_(0.68 * hall.clear_semi_axis_y) {
  // About 1 m/s along the ellipse (Ramanujan's perimeter approximation) or the figure of eight.
  const double a = semi_x_, b = semi_y_;
  const double ellipse = M_PI * (3 * (a + b) - std::sqrt((3 * a + b) * (a + 3 * b)));
  lap_time_ = kind == RouteKind::kFigure8 ? 1.25 * ellipse : ellipse;
}

Route::Route(RouteKind kind, RoundedPath path)
    : kind_(kind), path_(std::move(path)), lap_time_(path_->length() / kWalkingSpeed) {}

void Route::set_duration(double seconds) {
  if (kind_ == RouteKind::kKidnap) {
    cut_time_ = 0.6 * seconds;
    jump_ = 0.5 * lap_time_;  // back half a lap: a place the camera passed before the cut
  }
}

Eigen::Isometry3d Route::ContinuousPose(double t) const {
  const double w = 2 * M_PI / lap_time_;
  const double theta = w * t;
  Eigen::Vector3d position, velocity;
  if (path_) {
    const double walked = kWalkingSpeed * t;
    position << path_->Position(walked), 0;
    velocity << kWalkingSpeed * path_->Direction(walked), 0;
  } else if (kind_ == RouteKind::kFigure8) {
    // Gerono's lemniscate: x = a sin(theta), y = b sin(2 theta) / 1.2.
    position = {centre_.x() + semi_x_ * std::sin(theta),
                centre_.y() + semi_y_ * std::sin(2 * theta) / 1.2, 0};
    velocity = {semi_x_ * w * std::cos(theta), semi_y_ * 2 * w * std::cos(2 * theta) / 1.2, 0};
  } else {
    position = {centre_.x() + semi_x_ * std::cos(theta), centre_.y() + semi_y_ * std::sin(theta),
                0};
    velocity = {-semi_x_ * w * std::sin(theta), semi_y_ * w * std::cos(theta), 0};
  }
  position.z() = 1.4 + 0.25 * std::sin(2 * M_PI * t / 9.0);
  const double yaw = std::atan2(velocity.y(), velocity.x()) + 0.12 * std::sin(2 * M_PI * t / 5.3);
  const double pitch = 0.06 * std::sin(2 * M_PI * t / 7.1);
  const double roll = 0.05 * std::sin(2 * M_PI * t / 4.3);
  Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
  pose.linear() = (Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitZ()) *
                   Eigen::AngleAxisd(pitch, Eigen::Vector3d::UnitY()) *
                   Eigen::AngleAxisd(roll, Eigen::Vector3d::UnitX()))
                      .toRotationMatrix();
  pose.translation() = position;
  return pose;
}

std::vector<double> Route::Revisits(double duration) const {
  std::vector<double> revisits;
  bool inside = false;
  for (double t = 0.0; t <= duration; t += 0.1) {
    const Eigen::Isometry3d now = BodyPose(t);
    bool seen = false;
    for (double earlier = 0.0; earlier + 10.0 <= t && !seen; earlier += 0.1) {
      const Eigen::Isometry3d before = BodyPose(earlier);
      const double angle = Eigen::AngleAxisd(before.linear().transpose() * now.linear()).angle();
      seen = (now.translation() - before.translation()).norm() < 1.0 && angle < M_PI / 6;
    }
    if (seen && !inside) revisits.push_back(t);
    inside = seen;
  }
  return revisits;
}

Eigen::Isometry3d Route::BodyPose(double t) const {
  if (cut_time_ && t >= *cut_time_) return ContinuousPose(t - jump_);
  return ContinuousPose(t);
}

}  // namespace stereo_fabmap_slam::datasets
