#pragma once

#include <cstdint>
#include <limits>
#include <vector>

#include <Eigen/Core>

#include "stereo_fabmap_slam/datasets/texture_library.h"

namespace stereo_fabmap_slam::datasets {

// What a ray sees on a face: a grid of panels, each showing one texture stretched over it.
struct Material {
  std::vector<int> panel_textures;  // row-major, panel_columns x panel_rows, into textures()
  int panel_columns = 1, panel_rows = 1;
  float shade = 1.0f;  // per-face brightness, so that faces meeting at an edge differ
  // Panels run along the face's horizontal axis in its direction; a face seen from the side where
  // that axis points to the viewer's left is mirrored, so that text on it reads left to right.
  bool mirror_u = false;
  // A glossy floor: this fraction of what it shows is the blurred mirror image of the scene.
  float reflectance = 0.0f;
  // Derived when the scene is built: panels per metre along the face's two axes.
  float panels_per_metre_u = 0, panels_per_metre_v = 0;
};

// An axis-aligned box; faces in the order -x, +x, -y, +y, -z, +z.
struct Box {
  Eigen::Vector3f min, max;
  Material faces[6];
};

struct HallOptions {
  float length = 20.0f, width = 12.0f,
        height = 5.0f;       // [m] the hall spans [0, L] x [0, W] x [0, H]
  float panel_width = 2.5f;  // [m] photo panels along the walls
  int obstacle_boxes = 8;
  int pillars = 4;
  // Obstacles stay outside this ellipse around the hall centre, so that routes inside it are free.
  float clear_semi_axis_x = 7.2f, clear_semi_axis_y = 4.4f;
};

// A textured indoor hall of walls, floor and ceiling, with boxes and pillars, built from a seed
// (the same seed gives the same hall) and traced ray by ray.
class HallScene {
 public:
  HallScene(const HallOptions& options, const TextureLibrary& photos, std::uint64_t seed);
  // A scene of given boxes and textures (e.g. for tests); `boxes[0]` is the room seen from inside.
  HallScene(std::vector<Box> boxes, std::vector<Texture> textures);

  // Grey level (0-255) seen along a ray from `origin` in the unit `direction`; `pixel_angle` is the
  // angle a pixel spans [rad], for choosing the texture resolution. 0 if the ray leaves the hall.
  // `obstacles`: indices into boxes() that the ray may hit (e.g. ObstaclesInCone's);
  // all obstacles if null.
  float Trace(const Eigen::Vector3f& origin, const Eigen::Vector3f& direction, float pixel_angle,
              const std::vector<int>* obstacles = nullptr) const;
  // Obstacles that a ray from `origin` within `half_angle` [rad] of the unit `axis` may hit, in
  // the order of boxes(): those whose bounding sphere meets the cone. Every obstacle left out is
  // missed by every such ray, so tracing with this list gives what tracing with all does.
  std::vector<int> ObstaclesInCone(const Eigen::Vector3f& origin, const Eigen::Vector3f& axis,
                                   float half_angle) const;

  // Distance [m] along the unit `direction` from `origin` to the first surface (the exact
  // geometry, for measuring reconstructions); infinity if the ray leaves the hall.
  float Distance(const Eigen::Vector3f& origin, const Eigen::Vector3f& direction) const;
  // Distance [m] from a point to the nearest surface of the scene (walls, floor, ceiling,
  // obstacles): how far a reconstructed point lies from the exact geometry.
  float SurfaceDistance(const Eigen::Vector3f& point) const;

  const std::vector<Box>& boxes() const { return boxes_; }
  const std::vector<Texture>& textures() const { return textures_; }
  const HallOptions& options() const { return options_; }

 private:
  struct Hit {
    float distance = std::numeric_limits<float>::infinity();
    int box = -1;  // into boxes_; -1: none
    int face = 0;
  };
  Hit FirstHit(const Eigen::Vector3f& origin, const Eigen::Vector3f& direction,
               const std::vector<int>* obstacles) const;
  void DeriveScales();  // fills Material::panels_per_metre_*
  float TraceRay(const Eigen::Vector3f& origin, const Eigen::Vector3f& direction, float pixel_angle,
                 const std::vector<int>* obstacles, bool reflect) const;
  float Shade(const Box& box, int face, const Eigen::Vector3f& point, float distance,
              float cos_incidence, float pixel_angle) const;

  HallOptions options_;
  std::vector<Box> boxes_;  // boxes_[0]: the hall itself, seen from inside
  std::vector<Texture> textures_;
};

}  // namespace stereo_fabmap_slam::datasets
