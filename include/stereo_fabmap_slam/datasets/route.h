#pragma once

#include <optional>
#include <string>
#include <vector>

#include <Eigen/Geometry>

#include "stereo_fabmap_slam/datasets/hall_scene.h"
#include "stereo_fabmap_slam/datasets/rounded_path.h"

namespace stereo_fabmap_slam::datasets {

enum class RouteKind {
  kLoop,     // one lap around the hall and part of a second, back past the start the same way
  kFigure8,  // a figure of eight through the hall centre
  kKidnap,   // the loop, cut at 60 % of the time: the camera jumps back to a place seen earlier
};

std::optional<RouteKind> ParseRouteKind(const std::string& name);  // "loop", "figure8", "kidnap"
const char* RouteKindName(RouteKind kind);

// A smooth 6-DoF body trajectory at walking speed (about 1 m/s): body x forward, y left, z up,
// looking along the direction of travel with gentle yaw, pitch and roll oscillations and a slowly
// changing height. In the hall it follows an ellipse or a lemniscate inside the free ellipse; on
// an office floor, a path along the corridors.
class Route {
 public:
  Route(RouteKind kind, const HallOptions& hall);
  // Along `path` at 1 m/s, lap after lap; the kidnap route is `path` cut as in the hall.
  Route(RouteKind kind, RoundedPath path);

  Eigen::Isometry3d BodyPose(double t) const;  // T_world_body at t seconds
  // The kidnap route's cut: from `cut_time` on, the camera continues from where it was at
  // cut_time - jump. Empty for the other routes.
  std::optional<double> cut_time() const { return cut_time_; }
  double jump() const { return jump_; }
  double lap_time() const { return lap_time_; }
  // Times in [0, duration] when the camera comes back to a place it saw at least 10 s before:
  // within 1 m of an earlier position, heading within 30 degrees. Consecutive such moments count
  // as one revisit (the time of its first moment). These are the loops a place recognizer should
  // find.
  std::vector<double> Revisits(double duration) const;
  void set_duration(double seconds);

 private:
  Eigen::Isometry3d ContinuousPose(double t) const;

  RouteKind kind_;
  std::optional<RoundedPath> path_;  // the office's corridors; empty in the hall
  Eigen::Vector2d centre_;
  double semi_x_ = 0, semi_y_ = 0;
  double lap_time_;
  std::optional<double> cut_time_;
  double jump_ = 0;
};

}  // namespace stereo_fabmap_slam::datasets
