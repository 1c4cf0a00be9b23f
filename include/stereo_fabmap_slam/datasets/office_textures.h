#pragma once

#include <cstdint>

#include <opencv2/core.hpp>

namespace stereo_fabmap_slam::datasets {

// The surfaces of an office floor, drawn with OpenCV from a seed (no photographs, so that no
// vocabulary trained on photos has seen them): grey levels, kTexelsPerMetre texels a metre.
// Wall panels are `panel_width` wide and `height` tall, row 0 at the ceiling.
class OfficeTextures {
 public:
  static constexpr double kTexelsPerMetre = 400;

  OfficeTextures(double panel_width, double height) : width_(panel_width), height_(height) {}

  // Cream paint with a baseboard; variant 0 is bare, 1 has a light switch, 2 a power outlet, 3
  // scuff marks. `seed` draws the faint unevenness of the paint.
  cv::Mat Paint(int variant, std::uint64_t seed) const;
  // The one door design of a building, drawn from `seed` (leaf finish, glass, kick plate,
  // handle, hinge side, frame); with an exit sign above it if asked.
  cv::Mat Door(bool exit_sign, std::uint64_t seed) const;
  cv::Mat Poster(std::uint64_t seed) const;       // a framed poster: title, picture, small print
  cv::Mat NoticeBoard(std::uint64_t seed) const;  // cork with pinned sheets of text
  cv::Mat FireExtinguisher() const;
  // The lobby: one half (`half` 0 or 1) of the company's name, drawn from `seed`, on a dark
  // plate, and abstract art.
  cv::Mat Logo(int half, std::uint64_t seed) const;
  cv::Mat Art(std::uint64_t seed) const;
  // The kitchen corner: tiled splashback between lower and upper cupboards.
  cv::Mat KitchenWall(std::uint64_t seed) const;

  // Squares of `metres` on a side: floor linoleum, a ceiling tile, a ceiling light.
  static cv::Mat Linoleum(double metres, std::uint64_t seed);
  static cv::Mat CeilingTile(double metres, std::uint64_t seed);
  static cv::Mat CeilingLight(double metres);
  // Surfaces of furniture, `size` metres: wood (desk), leaves (plant), appliance (fridge front).
  static cv::Mat Wood(const cv::Size2d& size, std::uint64_t seed);
  static cv::Mat Leaves(const cv::Size2d& size, std::uint64_t seed);
  static cv::Mat Appliance(const cv::Size2d& size);

 private:
  cv::Mat Blank(std::uint64_t seed) const;  // paint and baseboard
  // Texels of a point `x` metres from the panel's left edge and `z` metres above the floor.
  cv::Point At(double x, double z) const;
  cv::Rect Area(double x0, double z0, double x1, double z1) const;  // corners in metres

  double width_, height_;
};

}  // namespace stereo_fabmap_slam::datasets
