#pragma once

#include <cstdint>

#include <Eigen/Geometry>

#include "stereo_fabmap_slam/datasets/hall_scene.h"
#include "stereo_fabmap_slam/datasets/rounded_path.h"
#include "stereo_fabmap_slam/datasets/route.h"

namespace stereo_fabmap_slam::datasets {

struct OfficeOptions {
  // [m] the floor spans [0, L] x [0, W] x [0, H]: corridors of `corridor_width` along its four
  // sides and across its middle, around two blocks of offices.
  float length = 30.0f, width = 15.0f, height = 2.7f;
  float corridor_width = 2.0f;
  float panel_width = 1.5f;  // [m] wall panels: a door on every third, the rest mostly paint

  void Validate() const;  // throws std::invalid_argument
};

// An office floor that looks like a real building: long corridors of plain cream paint, the
// building's one door design (each seed draws its own, as each seed is another building)
// repeated at a fixed spacing, suspended ceilings with a light every 3 m, a glossy
// floor, and posters, notice boards, fire extinguishers and exit signs that repeat from corridor
// to corridor; a lobby (company name, art, a reception desk, a plant) and a kitchen corner
// (cupboards, tiles, a counter, a fridge) are the only distinctive places. Everything is drawn
// from the seed: no photograph papers it.
//
// Plan (x along the length, y across): the lobby takes the corner at the origin, the kitchen an
// alcove off the far corner; the middle corridor joins the two long ones at two junctions.
class OfficeFloor {
 public:
  static HallScene Scene(const OfficeOptions& options, std::uint64_t seed);
  // The routes along the corridors' centre lines, corners rounded at 1 m:
  //  loop, kidnap: once around the outer corridors, start in the lobby corner;
  //  figure8: up the middle corridor and around the far block, then up the middle corridor again
  //           and around the near block: the middle corridor twice in the same direction, the
  //           two junctions crossed in different directions.
  static RoundedPath Path(RouteKind kind, const OfficeOptions& options);

  // The distinctive corners, [m] in the floor's plan: min and max corner.
  static Eigen::AlignedBox2d Lobby(const OfficeOptions& options);
  static Eigen::AlignedBox2d Kitchen(const OfficeOptions& options);
};

}  // namespace stereo_fabmap_slam::datasets
