#include "stereo_fabmap_slam/datasets/hall_scene.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <random>

namespace stereo_fabmap_slam::datasets {
namespace {

// Bilinear sample of an 8-bit image at (x, y), clamped to its border.
float Bilinear(const cv::Mat& image, float x, float y) {
  x = std::clamp(x, 0.0f, static_cast<float>(image.cols - 1) - 1e-3f);
  y = std::clamp(y, 0.0f, static_cast<float>(image.rows - 1) - 1e-3f);
  const int x0 = static_cast<int>(x), y0 = static_cast<int>(y);
  const float fx = x - x0, fy = y - y0;
  const std::uint8_t* row0 = image.ptr<std::uint8_t>(y0) + x0;
  const std::uint8_t* row1 = image.ptr<std::uint8_t>(y0 + 1) + x0;
  return (1 - fy) * ((1 - fx) * row0[0] + fx * row0[1]) + fy * ((1 - fx) * row1[0] + fx * row1[1]);
}

// The two in-plane axes of a face (indices into x, y, z): horizontal first, then vertical for
// walls; x then y for floors and ceilings.
void FaceAxes(int face, int* u_axis, int* v_axis) {
  const int normal = face / 2;
  if (normal == 2) {
    *u_axis = 0;
    *v_axis = 1;
  } else {
    *u_axis = normal == 0 ? 1 : 0;
    *v_axis = 2;
  }
}

Material PanelMaterial(float extent_u, float extent_v, float panel_width, float shade,
                       const std::vector<int>& photo_ids, std::mt19937_64* random) {
  Material material;
  material.panel_columns = std::max(1, static_cast<int>(std::round(extent_u / panel_width)));
  material.panel_rows = std::max(1, static_cast<int>(std::round(extent_v / (0.75f * panel_width))));
  material.shade = shade;
  std::uniform_int_distribution<std::size_t> pick(0, photo_ids.size() - 1);
  for (int i = 0; i < material.panel_columns * material.panel_rows; ++i) {
    material.panel_textures.push_back(photo_ids[pick(*random)]);
  }
  return material;
}

}  // namespace

HallScene::HallScene(std::vector<Box> boxes, std::vector<Texture> textures)
    : boxes_(std::move(boxes)), textures_(std::move(textures)) {
  DeriveScales();
}

void HallScene::DeriveScales() {
  for (Box& box : boxes_) {
    for (int face = 0; face < 6; ++face) {
      int u_axis, v_axis;
      FaceAxes(face, &u_axis, &v_axis);
      Material& material = box.faces[face];
      material.panels_per_metre_u = material.panel_columns / (box.max[u_axis] - box.min[u_axis]);
      material.panels_per_metre_v = material.panel_rows / (box.max[v_axis] - box.min[v_axis]);
    }
  }
}

HallScene::HallScene(const HallOptions& options, const TextureLibrary& photos, std::uint64_t seed)
    : options_(options) {
  std::mt19937_64 random(seed);
  textures_ = photos.photos();
  std::vector<int> photo_ids(textures_.size());
  for (std::size_t i = 0; i < photo_ids.size(); ++i) photo_ids[i] = static_cast<int>(i);
  const int floor_texture = static_cast<int>(textures_.size());
  textures_.push_back(TextureLibrary::Procedural(2048, seed * 2 + 1));
  const int ceiling_texture = static_cast<int>(textures_.size());
  textures_.push_back(TextureLibrary::Procedural(1024, seed * 2 + 2));

  // The hall: every wall panel draws a photo at random, so most areas differ and, with ~60
  // panels over ~60 photos, a few photos appear twice, as similar places do in real buildings.
  const float L = options.length, W = options.width, H = options.height;
  Box hall;
  hall.min = Eigen::Vector3f(0, 0, 0);
  hall.max = Eigen::Vector3f(L, W, H);
  const float wall_shades[4] = {1.0f, 0.85f, 0.95f, 0.8f};
  for (int face = 0; face < 4; ++face) {
    const float extent_u = face < 2 ? W : L;
    hall.faces[face] =
        PanelMaterial(extent_u, H, options.panel_width, wall_shades[face], photo_ids, &random);
  }
  hall.faces[4] = Material{{floor_texture}, 1, 1, 0.9f};
  hall.faces[5] = Material{{ceiling_texture}, 1, 1, 0.7f};
  boxes_.push_back(hall);

  // Obstacles between the free ellipse around the centre and the walls.
  std::uniform_real_distribution<float> unit(0.0f, 1.0f);
  const auto outside_clear_region = [&](float x0, float y0, float x1, float y1) {
    for (const float x : {x0, x1, 0.5f * (x0 + x1)}) {
      for (const float y : {y0, y1, 0.5f * (y0 + y1)}) {
        const float dx = (x - 0.5f * L) / options.clear_semi_axis_x;
        const float dy = (y - 0.5f * W) / options.clear_semi_axis_y;
        if (dx * dx + dy * dy < 1.0f) return false;
      }
    }
    return x0 > 0.2f && y0 > 0.2f && x1 < L - 0.2f && y1 < W - 0.2f;
  };
  const auto add_box = [&](float size_x, float size_y, float size_z) {
    for (int attempt = 0; attempt < 200; ++attempt) {
      const float x = unit(random) * (L - size_x), y = unit(random) * (W - size_y);
      if (!outside_clear_region(x, y, x + size_x, y + size_y)) continue;
      Box box;
      box.min = Eigen::Vector3f(x, y, 0.0f);
      box.max = Eigen::Vector3f(x + size_x, y + size_y, size_z);
      const float shades[6] = {0.9f, 0.75f, 0.85f, 0.7f, 0.6f, 1.0f};
      for (int face = 0; face < 6; ++face) {
        int u_axis, v_axis;
        FaceAxes(face, &u_axis, &v_axis);
        const float extent_u = box.max[u_axis] - box.min[u_axis];
        box.faces[face] = PanelMaterial(extent_u, box.max[v_axis] - box.min[v_axis],
                                        std::max(extent_u, 1.0f), shades[face], photo_ids, &random);
      }
      boxes_.push_back(box);
      return;
    }
  };
  for (int i = 0; i < options.obstacle_boxes; ++i) {
    add_box(0.8f + 1.2f * unit(random), 0.8f + 1.2f * unit(random), 0.6f + 1.6f * unit(random));
  }
  for (int i = 0; i < options.pillars; ++i) add_box(0.5f, 0.5f, H);
  DeriveScales();
}

float HallScene::Shade(const Box& box, int face, const Eigen::Vector3f& point, float distance,
                       float cos_incidence, float pixel_angle) const {
  int u_axis, v_axis;
  FaceAxes(face, &u_axis, &v_axis);
  const Material& material = box.faces[face];
  float u = (point[u_axis] - box.min[u_axis]) * material.panels_per_metre_u;
  if (material.mirror_u) u = material.panel_columns - u;
  // Textures stand upright on walls: image row 0 at the top.
  const float v = (box.max[v_axis] - point[v_axis]) * material.panels_per_metre_v;
  const int column = std::clamp(static_cast<int>(u), 0, material.panel_columns - 1);
  const int row = std::clamp(static_cast<int>(v), 0, material.panel_rows - 1);
  const Texture& texture =
      textures_[material.panel_textures[row * material.panel_columns + column]];
  const cv::Mat& full = texture.levels[0];
  // Texels one pixel covers; the pyramid level that brings it to about one (the binary
  // exponent of the footprint: floor(log2) without a logarithm).
  const float footprint = distance * pixel_angle / std::max(cos_incidence, 0.2f) * full.cols *
                          material.panels_per_metre_u;
  const int level = footprint < 2.0f ? 0
                                     : std::min(std::ilogb(footprint),
                                                static_cast<int>(texture.levels.size()) - 1);
  const float scale = texture.scales[static_cast<std::size_t>(level)];
  // Texel i covers [i, i + 1) of the texture; its value belongs to its centre, i + 0.5.
  return material.shade * Bilinear(texture.levels[static_cast<std::size_t>(level)],
                                   (u - column) * full.cols * scale - 0.5f,
                                   (v - row) * full.rows * scale - 0.5f);
}

std::vector<int> HallScene::ObstaclesInCone(const Eigen::Vector3f& origin,
                                            const Eigen::Vector3f& axis, float half_angle) const {
  // A ray within the cone hits a sphere only if the angle from the axis to the sphere's centre
  // is at most the cone's half-angle plus the angle the sphere subtends (triangle inequality
  // on angles). The slack covers rounding: Trace's float slab test may count a ray that misses
  // a box by a few ulps as a hit, and 1 mrad is a centimetre at 10 m, far beyond that.
  constexpr double kSlack = 1e-3;  // [rad]
  const Eigen::Vector3d apex = origin.cast<double>(), direction = axis.cast<double>().normalized();
  std::vector<int> in_cone;
  for (std::size_t b = 1; b < boxes_.size(); ++b) {
    const Eigen::Vector3d min = boxes_[b].min.cast<double>(), max = boxes_[b].max.cast<double>();
    const double radius = 0.5 * (max - min).norm();
    const Eigen::Vector3d to_centre = 0.5 * (min + max) - apex;
    const double distance = to_centre.norm();
    const bool inside = distance <= radius;
    if (inside || std::acos(std::clamp(to_centre.dot(direction) / distance, -1.0, 1.0)) <=
                      half_angle + std::asin(radius / distance) + kSlack) {
      in_cone.push_back(static_cast<int>(b));
    }
  }
  return in_cone;
}

float HallScene::Trace(const Eigen::Vector3f& origin, const Eigen::Vector3f& direction,
                       float pixel_angle, const std::vector<int>* obstacles) const {
  return TraceRay(origin, direction, pixel_angle, obstacles, /*reflect=*/true);
}

HallScene::Hit HallScene::FirstHit(const Eigen::Vector3f& origin, const Eigen::Vector3f& direction,
                                   const std::vector<int>* obstacles) const {
  const Eigen::Vector3f inverse = direction.cwiseInverse();
  Hit hit;
  // The hall: where the ray leaves it.
  const Box& hall = boxes_[0];
  for (int axis = 0; axis < 3; ++axis) {
    if (direction[axis] == 0.0f) continue;
    const bool positive = direction[axis] > 0.0f;
    const float t = ((positive ? hall.max[axis] : hall.min[axis]) - origin[axis]) * inverse[axis];
    if (t > 0.0f && t < hit.distance) {
      hit.distance = t;
      hit.box = 0;
      hit.face = 2 * axis + (positive ? 1 : 0);
    }
  }
  // Obstacles: where the ray enters them (slab test).
  const std::size_t count = obstacles ? obstacles->size() : boxes_.size() - 1;
  for (std::size_t k = 0; k < count; ++k) {
    const std::size_t b = obstacles ? static_cast<std::size_t>((*obstacles)[k]) : k + 1;
    const Box& box = boxes_[b];
    float near = -std::numeric_limits<float>::infinity(),
          far = std::numeric_limits<float>::infinity();
    int near_axis = 0;
    for (int axis = 0; axis < 3; ++axis) {
      float t0 = (box.min[axis] - origin[axis]) * inverse[axis];
      float t1 = (box.max[axis] - origin[axis]) * inverse[axis];
      if (t0 > t1) std::swap(t0, t1);
      if (t0 > near) {
        near = t0;
        near_axis = axis;
      }
      far = std::min(far, t1);
    }
    if (near <= far && near > 0.0f && near < hit.distance) {
      hit.distance = near;
      hit.box = static_cast<int>(b);
      hit.face =
          2 * near_axis + (direction[near_axis] > 0.0f ? 0 : 1);  // entering through min or max
    }
  }
  return hit;
}

float HallScene::Distance(const Eigen::Vector3f& origin, const Eigen::Vector3f& direction) const {
  return FirstHit(origin, direction, nullptr).distance;
}

float HallScene::SurfaceDistance(const Eigen::Vector3f& point) const {
  // Distance to a box's surface from inside it: to its nearest face; from outside: to the box.
  const auto to_surface = [&point](const Box& box) {
    const Eigen::Vector3f below = box.min - point, above = point - box.max;
    const Eigen::Vector3f outside = below.cwiseMax(above).cwiseMax(0.0f);
    if (outside.squaredNorm() > 0.0f) return outside.norm();
    return (-below).cwiseMin(-above).minCoeff();
  };
  float nearest = to_surface(boxes_[0]);
  for (std::size_t b = 1; b < boxes_.size(); ++b)
    nearest = std::min(nearest, to_surface(boxes_[b]));
  return nearest;
}

float HallScene::TraceRay(const Eigen::Vector3f& origin, const Eigen::Vector3f& direction,
                          float pixel_angle, const std::vector<int>* obstacles,
                          bool reflect) const {
  const Hit hit = FirstHit(origin, direction, obstacles);
  if (hit.box < 0) return 0.0f;
  const Eigen::Vector3f point = origin + hit.distance * direction;
  const float cos_incidence = std::abs(direction[hit.face / 2]);
  const Material& material = boxes_[static_cast<std::size_t>(hit.box)].faces[hit.face];
  const float own = Shade(boxes_[static_cast<std::size_t>(hit.box)], hit.face, point, hit.distance,
                          cos_incidence, pixel_angle);
  if (!reflect || material.reflectance <= 0.0f) return own;
  // One bounce, against every obstacle (the cone's list holds for the primary rays only), with
  // a footprint four times wider: a waxed floor shows a blurred image, not a mirror's.
  Eigen::Vector3f mirrored = direction;
  mirrored[hit.face / 2] = -mirrored[hit.face / 2];
  const float reflected = TraceRay(point, mirrored, 4.0f * pixel_angle, nullptr, false);
  return (1.0f - material.reflectance) * own + material.reflectance * reflected;
}

}  // namespace stereo_fabmap_slam::datasets
