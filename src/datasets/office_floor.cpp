#include "stereo_fabmap_slam/datasets/office_floor.h"

#include <algorithm>
#include <cmath>
#include <functional>
#include <random>
#include <stdexcept>

#include "stereo_fabmap_slam/datasets/office_textures.h"
#include "stereo_fabmap_slam/datasets/texture_library.h"

namespace stereo_fabmap_slam::datasets {
namespace {

constexpr float kLobbyDepth = 4.0f, kLobbyWidth = 3.0f;       // [m] beyond the corridors
constexpr float kKitchenLength = 5.0f, kKitchenDepth = 3.0f;  // [m] the alcove
constexpr float kCeilingCell = 0.5f, kFloorCell = 2.0f;       // [m]
constexpr float kLightSpacing = 3.0f;  // [m] along a corridor, as in most office buildings

// The textures of the floor, by what they show; indices into the scene's texture list.
struct Palette {
  std::vector<Texture> textures;
  std::vector<int> paint, posters, notice_boards, art, kitchen, ceiling_tiles, linoleum;
  int door = 0, exit_door = 0, extinguisher = 0, logo[2] = {0, 0}, ceiling_light = 0;

  int Add(const cv::Mat& grey, const std::string& name) {
    textures.push_back(TextureLibrary::FromImage(grey, name));
    return static_cast<int>(textures.size()) - 1;
  }
};

Palette MakePalette(const OfficeOptions& options, std::uint64_t seed) {
  const OfficeTextures draw(options.panel_width, options.height);
  Palette palette;
  // Two of each paint variant: blank walls that look alike without being pixel copies.
  for (int variant = 0; variant < 4; ++variant) {
    for (int copy = 0; copy < 2; ++copy) {
      palette.paint.push_back(palette.Add(draw.Paint(variant, seed * 97 + variant * 2 + copy),
                                          "paint " + std::to_string(variant)));
    }
  }
  // One door design for the whole building, the exit sign's door included.
  palette.door = palette.Add(draw.Door(false, seed * 59), "door");
  palette.exit_door = palette.Add(draw.Door(true, seed * 59), "door with exit sign");
  palette.extinguisher = palette.Add(draw.FireExtinguisher(), "fire extinguisher");
  for (int k = 0; k < 3; ++k)
    palette.posters.push_back(palette.Add(draw.Poster(seed * 31 + k), "poster"));
  for (int k = 0; k < 2; ++k)
    palette.notice_boards.push_back(palette.Add(draw.NoticeBoard(seed * 37 + k), "notice board"));
  for (int half = 0; half < 2; ++half)
    palette.logo[half] = palette.Add(draw.Logo(half, seed * 61), "logo");
  for (int k = 0; k < 6; ++k) palette.art.push_back(palette.Add(draw.Art(seed * 41 + k), "art"));
  for (int k = 0; k < 2; ++k)
    palette.kitchen.push_back(palette.Add(draw.KitchenWall(seed * 43 + k), "kitchen"));
  for (int k = 0; k < 3; ++k) {
    palette.ceiling_tiles.push_back(
        palette.Add(OfficeTextures::CeilingTile(kCeilingCell, seed * 47 + k), "ceiling tile"));
    palette.linoleum.push_back(
        palette.Add(OfficeTextures::Linoleum(kFloorCell, seed * 53 + k), "linoleum"));
  }
  palette.ceiling_light = palette.Add(OfficeTextures::CeilingLight(kCeilingCell), "light");
  return palette;
}

// The two in-plane axes of a wall face (HallScene's convention): y for faces 0 and 1, x else.
int HorizontalAxis(int face) { return face < 2 ? 1 : 0; }

// A wall of panels, the first at the face's low end; `content(k, centre)` picks panel k's
// texture from the panel centre's position in the plan. `seen_from_inside`: the room's walls.
Material WallMaterial(const Box& box, int face, bool seen_from_inside, float panel_width,
                      float shade, const std::function<int(int, const Eigen::Vector2f&)>& content) {
  const int axis = HorizontalAxis(face);
  const float extent = box.max[axis] - box.min[axis];
  Material material;
  material.panel_columns = std::max(1, static_cast<int>(std::lround(extent / panel_width)));
  material.panel_rows = 1;
  material.shade = shade;
  // The side a viewer stands on decides whether the face's axis runs to their right.
  const bool mirrored_outside = face == 0 || face == 3;
  material.mirror_u = seen_from_inside ? !mirrored_outside : mirrored_outside;
  const float step = extent / material.panel_columns;
  const int normal = face / 2;
  const float plane = face % 2 == 0 ? box.min[normal] : box.max[normal];
  for (int k = 0; k < material.panel_columns; ++k) {
    Eigen::Vector2f centre;
    centre[axis] = box.min[axis] + (k + 0.5f) * step;
    centre[normal] = plane;
    material.panel_textures.push_back(content(k, centre));
  }
  if (material.mirror_u) {
    std::reverse(material.panel_textures.begin(), material.panel_textures.end());
  }
  return material;
}

Box SolidBox(const Eigen::Vector3f& min, const Eigen::Vector3f& max) {
  Box box;
  box.min = min;
  box.max = max;
  return box;
}

}  // namespace

void OfficeOptions::Validate() const {
  if (!(corridor_width >= 1.5f && corridor_width <= 4.0f))
    throw std::invalid_argument("corridor width must lie in [1.5, 4] m");
  if (!(height >= 2.2f && height <= 5.0f))
    throw std::invalid_argument("office height must lie in [2.2, 5] m");
  if (!(panel_width >= 1.2f && panel_width <= 3.0f))
    throw std::invalid_argument("panel width must lie in [1.2, 3] m");
  // The lobby and the kitchen need a block of at least 2 m beside them.
  const float shortest = 3 * corridor_width + 2 * (std::max(kLobbyDepth, kKitchenLength) + 2);
  if (!(length >= shortest))
    throw std::invalid_argument("the office is too short for its lobby and kitchen");
  if (!(width >= 2 * corridor_width + std::max(kKitchenDepth, kLobbyWidth) + 2))
    throw std::invalid_argument("the office is too narrow for its lobby and kitchen");
}

Eigen::AlignedBox2d OfficeFloor::Lobby(const OfficeOptions& options) {
  return Eigen::AlignedBox2d(
      Eigen::Vector2d(0, 0),
      Eigen::Vector2d(options.corridor_width + kLobbyDepth, options.corridor_width + kLobbyWidth));
}

Eigen::AlignedBox2d OfficeFloor::Kitchen(const OfficeOptions& options) {
  const double far_x = options.length - options.corridor_width;
  const double far_y = options.width - options.corridor_width;
  return Eigen::AlignedBox2d(Eigen::Vector2d(far_x - kKitchenLength, far_y - kKitchenDepth),
                             Eigen::Vector2d(far_x, far_y));
}

HallScene OfficeFloor::Scene(const OfficeOptions& options, std::uint64_t seed) {
  options.Validate();
  Palette palette = MakePalette(options, seed);
  std::mt19937_64 random(seed);
  const float L = options.length, W = options.width, H = options.height;
  const float c = options.corridor_width;
  const Eigen::AlignedBox2d lobby = Lobby(options), kitchen = Kitchen(options);
  const auto inside = [](const Eigen::AlignedBox2d& area, const Eigen::Vector2f& point) {
    return (point.cast<double>().array() >= area.min().array() - 0.01).all() &&
           (point.cast<double>().array() <= area.max().array() + 0.01).all();
  };

  // What a corridor wall shows: a door on every third panel, the rest paint, with now and then
  // something hung on it from the few kinds every corridor has.
  std::uniform_int_distribution<std::size_t> paint(0, palette.paint.size() - 1);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  std::uniform_int_distribution<int> decoration(0, 5);
  int lobby_panel = 0;
  const auto corridor_wall = [&](bool outer_wall) {
    return [&, outer_wall, first_door = true](int k, const Eigen::Vector2f& centre) mutable {
      if (inside(lobby, centre)) {
        // The company's name on the wall facing the entrance, art on the others. Seen from the
        // lobby, that wall's +x runs to the left: the name's first half is at the larger x.
        if (centre.y() < 0.01f && std::abs(centre.x() - lobby.center().x()) < options.panel_width)
          return palette.logo[centre.x() > lobby.center().x() ? 0 : 1];
        return palette.art[static_cast<std::size_t>(lobby_panel++) % palette.art.size()];
      }
      if (inside(kitchen, centre)) return palette.kitchen[static_cast<std::size_t>(k) % 2];
      if (k % 3 == 1) {
        const bool exit = outer_wall && first_door;
        first_door = false;
        return exit ? palette.exit_door : palette.door;
      }
      if (unit(random) < 0.7) return palette.paint[paint(random)];
      switch (decoration(random)) {
        case 0:
        case 1:
        case 2:
          return palette.posters[static_cast<std::size_t>(decoration(random)) % 3];
        case 3:
        case 4:
          return palette.notice_boards[static_cast<std::size_t>(decoration(random)) % 2];
        default:
          return palette.extinguisher;
      }
    };
  };
  const float wall_shades[4] = {0.96f, 0.88f, 1.0f, 0.92f};

  std::vector<Box> boxes;
  Box room = SolidBox(Eigen::Vector3f(0, 0, 0), Eigen::Vector3f(L, W, H));
  for (int face = 0; face < 4; ++face) {
    room.faces[face] = WallMaterial(room, face, /*seen_from_inside=*/true, options.panel_width,
                                    wall_shades[face], corridor_wall(true));
  }
  Material& floor = room.faces[4];
  floor.panel_columns = std::max(1, static_cast<int>(std::lround(L / kFloorCell)));
  floor.panel_rows = std::max(1, static_cast<int>(std::lround(W / kFloorCell)));
  std::uniform_int_distribution<std::size_t> linoleum(0, palette.linoleum.size() - 1);
  for (int i = 0; i < floor.panel_columns * floor.panel_rows; ++i)
    floor.panel_textures.push_back(palette.linoleum[linoleum(random)]);
  floor.shade = 0.9f;
  floor.reflectance = 0.2f;
  // The ceiling: tiles, and a light every 3 m down the middle of each corridor.
  Material& ceiling = room.faces[5];
  ceiling.panel_columns = std::max(1, static_cast<int>(std::lround(L / kCeilingCell)));
  ceiling.panel_rows = std::max(1, static_cast<int>(std::lround(W / kCeilingCell)));
  const float cell_x = L / ceiling.panel_columns, cell_y = W / ceiling.panel_rows;
  std::uniform_int_distribution<std::size_t> tile(0, palette.ceiling_tiles.size() - 1);
  const float corridor_x[3] = {0.5f * c, 0.5f * L, L - 0.5f * c};
  const float corridor_y[2] = {0.5f * c, W - 0.5f * c};
  // A light is one cell along the corridor and the two cells across its centre line.
  const auto lit = [&](float along) {
    const float phase = std::fmod(along, kLightSpacing);
    return std::abs(phase - 0.5f * (kLightSpacing - kCeilingCell)) < 0.5f * kCeilingCell;
  };
  for (int row = 0; row < ceiling.panel_rows; ++row) {
    for (int column = 0; column < ceiling.panel_columns; ++column) {
      // Row 0 is at y = W (textures stand upright: rows run against the face's second axis).
      const float x = (column + 0.5f) * cell_x, y = W - (row + 0.5f) * cell_y;
      bool light = false;
      for (const float cx : corridor_x) light |= std::abs(x - cx) < kCeilingCell && lit(y);
      for (const float cy : corridor_y) light |= std::abs(y - cy) < kCeilingCell && lit(x);
      ceiling.panel_textures.push_back(light ? palette.ceiling_light
                                             : palette.ceiling_tiles[tile(random)]);
    }
  }
  ceiling.shade = 1.0f;
  boxes.push_back(room);

  // The two blocks of offices, cut back for the lobby and the kitchen, each as two boxes.
  const float middle_low = 0.5f * (L - c), middle_high = 0.5f * (L + c);
  const float lobby_x = static_cast<float>(lobby.max().x()),
              lobby_y = static_cast<float>(lobby.max().y());
  const float kitchen_x = static_cast<float>(kitchen.min().x()),
              kitchen_y = static_cast<float>(kitchen.min().y());
  const Box blocks[4] = {
      SolidBox({lobby_x, c, 0}, {middle_low, W - c, H}),
      SolidBox({c, lobby_y, 0}, {lobby_x, W - c, H}),
      SolidBox({middle_high, c, 0}, {L - c, kitchen_y, H}),
      SolidBox({middle_high, kitchen_y, 0}, {kitchen_x, W - c, H}),
  };
  for (Box block : blocks) {
    for (int face = 0; face < 4; ++face) {
      block.faces[face] = WallMaterial(block, face, /*seen_from_inside=*/false, options.panel_width,
                                       wall_shades[face], corridor_wall(false));
    }
    block.faces[4] = block.faces[5] = Material{{palette.paint[0]}, 1, 1, 1.0f};
    boxes.push_back(block);
  }

  // Furniture: a reception desk and a plant in the lobby, a counter and a fridge in the kitchen.
  const auto furnish = [&](const Eigen::Vector3f& min, const Eigen::Vector3f& max, float shade,
                           const std::function<cv::Mat(const cv::Size2d&, int)>& surface) {
    Box box = SolidBox(min, max);
    for (int face = 0; face < 6; ++face) {
      const int u = face / 2 == 2 ? 0 : HorizontalAxis(face), v = face / 2 == 2 ? 1 : 2;
      const cv::Size2d size(max[u] - min[u], max[v] - min[v]);
      const int texture = palette.Add(surface(size, face), "furniture");
      box.faces[face] =
          Material{{texture}, 1, 1, shade * (face == 5 ? 1.0f : 0.85f + 0.03f * face)};
    }
    boxes.push_back(box);
  };
  const auto wood = [&](const cv::Size2d& size, int face) {
    return OfficeTextures::Wood(size, seed * 59 + static_cast<std::uint64_t>(face));
  };
  const auto leaves = [&](const cv::Size2d& size, int face) {
    return OfficeTextures::Leaves(size, seed * 61 + static_cast<std::uint64_t>(face));
  };
  const auto appliance = [](const cv::Size2d& size, int) {
    return OfficeTextures::Appliance(size);
  };
  const float lx = static_cast<float>(lobby.min().x()), ly = static_cast<float>(lobby.min().y());
  furnish({lx + c + 1.0f, ly + c + 0.6f, 0}, {lx + c + 3.0f, ly + c + 1.3f, 1.1f}, 1.0f, wood);
  furnish({lobby_x - 0.8f, lobby_y - 0.7f, 0}, {lobby_x - 0.3f, lobby_y - 0.2f, 1.2f}, 1.0f,
          leaves);
  furnish({kitchen_x, kitchen_y, 0}, {kitchen_x + 0.7f, kitchen_y + 0.7f, 1.8f}, 1.0f, appliance);
  furnish({kitchen_x + 0.7f, kitchen_y, 0}, {kitchen_x + 4.2f, kitchen_y + 0.6f, 0.9f}, 0.9f, wood);

  return HallScene(std::move(boxes), std::move(palette.textures));
}

RoundedPath OfficeFloor::Path(RouteKind kind, const OfficeOptions& options) {
  options.Validate();
  const double L = options.length, W = options.width, h = 0.5 * options.corridor_width;
  const Eigen::Vector2d near_low(h, h), far_low(L - h, h), far_high(L - h, W - h),
      near_high(h, W - h), middle_low(0.5 * L, h), middle_high(0.5 * L, W - h);
  constexpr double kCornerRadius = 1.0;  // [m] a walker keeps about a metre from a corner
  if (kind == RouteKind::kFigure8) {
    return RoundedPath(
        {middle_low, middle_high, far_high, far_low, middle_low, middle_high, near_high, near_low},
        kCornerRadius);
  }
  return RoundedPath({near_low, far_low, far_high, near_high}, kCornerRadius);
}

}  // namespace stereo_fabmap_slam::datasets
