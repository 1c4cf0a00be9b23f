#include "stereo_fabmap_slam/datasets/office_textures.h"

#include <algorithm>
#include <cmath>
#include <random>
#include <string>

#include <opencv2/imgproc.hpp>

#include "stereo_fabmap_slam/datasets/texture_library.h"

namespace stereo_fabmap_slam::datasets {
namespace {

int Texels(double metres) {
  return std::max(1, static_cast<int>(std::lround(metres * OfficeTextures::kTexelsPerMetre)));
}

// Smooth noise of the given size with values in [-1, 1] (value noise, as the hall's floor).
cv::Mat Unevenness(cv::Size size, std::uint64_t seed) {
  const cv::Mat grey = TextureLibrary::Procedural(512, seed).levels[0];
  cv::Mat noise;
  grey.convertTo(noise, CV_32F, 1.0 / 127.5, -1.0);
  cv::resize(noise, noise, size, 0, 0, cv::INTER_LINEAR);
  return noise;
}

// `base` grey with noise of `amplitude` grey levels.
cv::Mat Uneven(cv::Size size, double base, double amplitude, std::uint64_t seed) {
  cv::Mat surface = base + amplitude * Unevenness(size, seed);
  cv::Mat grey;
  surface.convertTo(grey, CV_8U);
  return grey;
}

std::string Word(std::mt19937_64* random, int min_letters, int max_letters) {
  std::uniform_int_distribution<int> letters(min_letters, max_letters), letter(0, 25);
  std::string word(static_cast<std::size_t>(letters(*random)), 'A');
  for (char& c : word) c = static_cast<char>('A' + letter(*random));
  return word;
}

// Lines of small print filling `area`: random words, as text on a sheet looks from a metre away.
void SmallPrint(cv::Mat* image, const cv::Rect& area, int line_height, double grey,
                std::mt19937_64* random) {
  const double scale = line_height / 22.0;
  for (int y = area.y + line_height; y < area.br().y; y += line_height + line_height / 2) {
    std::string line;
    while (true) {
      const std::string next = line + (line.empty() ? "" : " ") + Word(random, 2, 8);
      int baseline = 0;
      const cv::Size size = cv::getTextSize(next, cv::FONT_HERSHEY_PLAIN, scale, 1, &baseline);
      if (size.width > area.width) break;
      line = next;
    }
    cv::putText(*image, line, cv::Point(area.x, y), cv::FONT_HERSHEY_PLAIN, scale, cv::Scalar(grey),
                1, cv::LINE_AA);
  }
}

// Text centred in `area`, as large as fits.
void Title(cv::Mat* image, const std::string& text, const cv::Rect& area, double grey,
           int font = cv::FONT_HERSHEY_DUPLEX) {
  int baseline = 0;
  const int thickness = std::max(2, area.height / 12);
  const cv::Size unit = cv::getTextSize(text, font, 1.0, thickness, &baseline);
  const double scale = std::min(area.width * 0.9 / unit.width, area.height * 0.8 / unit.height);
  const cv::Size size = cv::getTextSize(text, font, scale, thickness, &baseline);
  cv::putText(
      *image, text,
      cv::Point(area.x + (area.width - size.width) / 2, area.y + (area.height + size.height) / 2),
      font, scale, cv::Scalar(grey), thickness, cv::LINE_AA);
}

}  // namespace

cv::Point OfficeTextures::At(double x, double z) const {
  return cv::Point(Texels(x), Texels(height_ - z));
}

cv::Rect OfficeTextures::Area(double x0, double z0, double x1, double z1) const {
  return cv::Rect(At(x0, z1), At(x1, z0));
}

cv::Mat OfficeTextures::Blank(std::uint64_t seed) const {
  // Cream paint: grey 178 with +-3 levels of unevenness, below the camera noise (2 levels) and
  // the sensor's quantisation at a distance: a wall that gives a detector almost nothing.
  cv::Mat panel = Uneven(cv::Size(Texels(width_), Texels(height_)), 178, 3, seed);
  cv::rectangle(panel, Area(0, 0, width_, 0.10), cv::Scalar(85), cv::FILLED);
  cv::rectangle(panel, Area(0, 0.095, width_, 0.10), cv::Scalar(60), cv::FILLED);
  return panel;
}

cv::Mat OfficeTextures::Paint(int variant, std::uint64_t seed) const {
  cv::Mat panel = Blank(seed);
  std::mt19937_64 random(seed);
  std::uniform_real_distribution<double> across(0.2, width_ - 0.2);
  if (variant == 1) {  // a light switch at 1.1 m
    const double x = across(random);
    cv::rectangle(panel, Area(x, 1.05, x + 0.08, 1.17), cv::Scalar(222), cv::FILLED);
    cv::rectangle(panel, Area(x, 1.05, x + 0.08, 1.17), cv::Scalar(150), 2);
    cv::rectangle(panel, Area(x + 0.025, 1.09, x + 0.055, 1.13), cv::Scalar(200), cv::FILLED);
  } else if (variant == 2) {  // a double power outlet at 0.3 m
    const double x = across(random);
    cv::rectangle(panel, Area(x, 0.26, x + 0.15, 0.34), cv::Scalar(215), cv::FILLED);
    for (const double socket : {x + 0.04, x + 0.11})
      cv::circle(panel, At(socket, 0.30), Texels(0.022), cv::Scalar(120), cv::FILLED);
  } else if (variant == 3) {  // scuffs where trolleys and chairs touched the wall
    std::uniform_real_distribution<double> height(0.15, 0.9), length(0.05, 0.3);
    for (int k = 0; k < 5; ++k) {
      const double x = across(random), z = height(random);
      cv::line(panel, At(x, z), At(x + length(random), z + 0.02), cv::Scalar(150), 2, cv::LINE_AA);
    }
  }
  return panel;
}

cv::Mat OfficeTextures::Door(bool exit_sign, std::uint64_t seed) const {
  // Every building has its own door (wood, light wood or paint; a glass panel or none; lever or
  // knob on either side; frame colour), repeated on every corridor of that building: a
  // vocabulary trained on one rendered office has not seen the next one's doors, as a real
  // building's are new to it.
  std::mt19937_64 random(seed);
  const auto pick = [&random](int count) {
    return std::uniform_int_distribution<int>(0, count - 1)(random);
  };
  cv::Mat panel = Blank(7);
  const double left = 0.5 * width_ - 0.48, right = 0.5 * width_ + 0.48;
  const double frame_grey[] = {205, 120, 60};
  cv::rectangle(panel, Area(left, 0, right, 2.15), cv::Scalar(frame_grey[pick(3)]),
                cv::FILLED);  // frame
  const cv::Rect leaf = Area(left + 0.05, 0, right - 0.05, 2.10);
  const int finish = pick(3);
  if (finish < 2) {
    // Wood grain: columns of slightly different darkness, stretched down the leaf.
    cv::Mat grain = Uneven(cv::Size(leaf.width, 8), finish == 0 ? 68 : 150, 7, seed + 11);
    cv::resize(grain, grain, leaf.size(), 0, 0, cv::INTER_LINEAR);
    grain.copyTo(panel(leaf));
  } else {  // paint, a shade away from the wall's
    Uneven(leaf.size(), 95 + 20 * pick(3), 2, seed + 12).copyTo(panel(leaf));
  }
  const int glass = pick(3);  // none, a narrow vertical pane, a square at eye height
  if (glass == 1) {
    cv::rectangle(panel, Area(left + 0.2, 1.1, left + 0.32, 1.9), cv::Scalar(40), cv::FILLED);
  } else if (glass == 2) {
    cv::rectangle(panel, Area(left + 0.3, 1.35, right - 0.3, 1.75), cv::Scalar(40), cv::FILLED);
  }
  if (pick(2) == 0) {
    cv::rectangle(panel, Area(left + 0.05, 0, right - 0.05, 0.25), cv::Scalar(120),
                  cv::FILLED);  // kick plate
  }
  const bool hinges_left = pick(2) == 0;
  const double handle_x = hinges_left ? right - 0.12 : left + 0.12;
  const double hinge_x = hinges_left ? left + 0.045 : right - 0.06;
  cv::circle(panel, At(handle_x, 1.0), Texels(0.03), cv::Scalar(200), cv::FILLED);  // rosette
  if (pick(2) == 0) {  // a lever towards the leaf's middle; else the rosette's knob alone
    const double towards = hinges_left ? -0.14 : 0.14;
    cv::rectangle(panel,
                  Area(std::min(handle_x, handle_x + towards), 0.99,
                       std::max(handle_x, handle_x + towards), 1.01),
                  cv::Scalar(215), cv::FILLED);
  } else {
    cv::circle(panel, At(handle_x, 1.0), Texels(0.018), cv::Scalar(150), cv::FILLED);
  }
  for (const double z : {0.3, 1.05, 1.8})
    cv::rectangle(panel, Area(hinge_x, z, hinge_x + 0.015, z + 0.1), cv::Scalar(150), cv::FILLED);
  if (exit_sign) {
    const cv::Rect sign = Area(0.5 * width_ - 0.2, 2.25, 0.5 * width_ + 0.2, 2.45);
    cv::rectangle(panel, sign, cv::Scalar(235), cv::FILLED);
    cv::rectangle(panel, sign, cv::Scalar(90), 3);
    Title(&panel, "EXIT", cv::Rect(sign.x, sign.y, sign.width * 2 / 3, sign.height), 45);
    const cv::Point tip(sign.br().x - sign.width / 12, sign.y + sign.height / 2);
    cv::arrowedLine(panel, cv::Point(sign.x + sign.width * 2 / 3, tip.y), tip, cv::Scalar(45), 4,
                    cv::LINE_AA, 0, 0.4);
  }
  return panel;
}

cv::Mat OfficeTextures::Poster(std::uint64_t seed) const {
  cv::Mat panel = Blank(seed + 100);
  std::mt19937_64 random(seed);
  std::uniform_int_distribution<int> grey(150, 245);
  const double left = 0.5 * width_ - 0.3, right = 0.5 * width_ + 0.3;
  const cv::Rect poster = Area(left, 1.0, right, 1.85);
  cv::rectangle(panel, poster, cv::Scalar(grey(random)), cv::FILLED);
  cv::rectangle(panel, poster, cv::Scalar(40), Texels(0.02));
  Title(&panel, Word(&random, 4, 7), Area(left + 0.04, 1.68, right - 0.04, 1.81), 30);
  // A picture: noise at a seed-chosen scale, contrasted like a photograph.
  const cv::Rect picture = Area(left + 0.05, 1.22, right - 0.05, 1.64);
  cv::Mat noise = TextureLibrary::Procedural(256, seed * 7 + 3).levels[0];
  cv::resize(noise, noise, picture.size(), 0, 0, cv::INTER_LINEAR);
  noise.copyTo(panel(picture));
  SmallPrint(&panel, Area(left + 0.04, 1.03, right - 0.04, 1.2), Texels(0.025), 40, &random);
  return panel;
}

cv::Mat OfficeTextures::NoticeBoard(std::uint64_t seed) const {
  cv::Mat panel = Blank(seed + 200);
  std::mt19937_64 random(seed);
  const double left = 0.15, right = width_ - 0.15;
  const cv::Rect board = Area(left, 0.95, right, 1.85);
  Uneven(board.size(), 135, 25, seed * 5 + 1).copyTo(panel(board));
  cv::rectangle(panel, board, cv::Scalar(95), Texels(0.025));
  std::uniform_real_distribution<double> x(left + 0.05, right - 0.3), z(1.0, 1.5);
  std::uniform_int_distribution<int> sheets(4, 7);
  for (int k = sheets(random); k > 0; --k) {
    const double x0 = x(random), z0 = z(random);
    const cv::Rect sheet = Area(x0, z0, x0 + 0.21, z0 + 0.297);
    cv::rectangle(panel, sheet, cv::Scalar(238), cv::FILLED);
    cv::rectangle(panel, sheet, cv::Scalar(200), 1);
    SmallPrint(&panel, cv::Rect(sheet.x + 8, sheet.y + 6, sheet.width - 16, sheet.height - 12),
               Texels(0.012), 60, &random);
    cv::circle(panel, cv::Point(sheet.x + sheet.width / 2, sheet.y + 5), 5, cv::Scalar(50),
               cv::FILLED);  // the pin
  }
  return panel;
}

cv::Mat OfficeTextures::FireExtinguisher() const {
  cv::Mat panel = Blank(300);
  const double x = 0.5 * width_;
  cv::rectangle(panel, Area(x - 0.1, 1.3, x + 0.1, 1.5), cv::Scalar(85), cv::FILLED);  // sign
  Title(&panel, "F", Area(x - 0.08, 1.32, x + 0.08, 1.48), 235);
  cv::rectangle(panel, Area(x - 0.09, 0.15, x + 0.09, 0.72), cv::Scalar(80), cv::FILLED);
  cv::ellipse(panel, At(x, 0.72), cv::Size(Texels(0.09), Texels(0.05)), 0, 180, 360, cv::Scalar(80),
              cv::FILLED);
  cv::rectangle(panel, Area(x - 0.05, 0.15, x - 0.03, 0.7), cv::Scalar(140), cv::FILLED);
  cv::rectangle(panel, Area(x - 0.04, 0.74, x + 0.04, 0.84), cv::Scalar(40), cv::FILLED);
  cv::line(panel, At(x + 0.04, 0.8), At(x + 0.14, 0.5), cv::Scalar(30), Texels(0.015), cv::LINE_AA);
  cv::rectangle(panel, Area(x - 0.13, 0.12, x + 0.13, 0.15), cv::Scalar(110), cv::FILLED);
  return panel;
}

cv::Mat OfficeTextures::Logo(int half, std::uint64_t seed) const {
  cv::Mat panel = Blank(400 + half);
  // The company's name, two words drawn from the seed: each building's own.
  std::mt19937_64 random(seed);
  const std::string first = Word(&random, 4, 7), second = Word(&random, 3, 6);
  cv::rectangle(panel, Area(half == 0 ? 0.2 : 0, 1.3, half == 0 ? width_ : width_ - 0.2, 2.1),
                cv::Scalar(45), cv::FILLED);
  Title(&panel, half == 0 ? first : second,
        Area(half == 0 ? 0.3 : 0.1, 1.45, half == 0 ? width_ - 0.1 : width_ - 0.3, 1.95), 235,
        cv::FONT_HERSHEY_TRIPLEX);
  return panel;
}

cv::Mat OfficeTextures::Art(std::uint64_t seed) const {
  cv::Mat panel = Blank(seed + 500);
  std::mt19937_64 random(seed);
  const cv::Rect canvas = Area(0.2, 0.8, width_ - 0.2, 2.2);
  cv::Mat art(canvas.size(), CV_8U, cv::Scalar(200));
  std::uniform_int_distribution<int> grey(10, 250), x(0, canvas.width), y(0, canvas.height),
      r(10, canvas.width / 3);
  for (int k = 0; k < 25; ++k) {
    if (k % 2 == 0) {
      cv::circle(art, cv::Point(x(random), y(random)), r(random), cv::Scalar(grey(random)),
                 cv::FILLED, cv::LINE_AA);
    } else {
      cv::rectangle(art, cv::Rect(x(random), y(random), r(random), r(random)),
                    cv::Scalar(grey(random)), cv::FILLED);
    }
  }
  art.copyTo(panel(canvas));
  cv::rectangle(panel, canvas, cv::Scalar(30), Texels(0.03));
  return panel;
}

cv::Mat OfficeTextures::KitchenWall(std::uint64_t seed) const {
  cv::Mat panel = Blank(seed + 600);
  // Lower cupboards (mostly behind the counter), splashback tiles, upper cupboards.
  const cv::Rect tiles = Area(0, 0.9, width_, 1.5);
  cv::rectangle(panel, tiles, cv::Scalar(150), cv::FILLED);
  const int tile = Texels(0.1), grout = std::max(2, Texels(0.006));
  for (int y = tiles.y; y < tiles.br().y; y += tile) {
    for (int x = tiles.x; x < tiles.br().x; x += tile) {
      cv::rectangle(panel, cv::Rect(x + grout, y + grout, tile - 2 * grout, tile - 2 * grout),
                    cv::Scalar(218), cv::FILLED);
    }
  }
  std::mt19937_64 random(seed);
  std::uniform_int_distribution<int> shade(190, 210);
  for (const auto& [z0, z1] : {std::pair<double, double>{1.5, 2.2}, {0.1, 0.88}}) {
    for (double x = 0; x + 0.49 <= width_ + 1e-9; x += 0.5) {
      cv::rectangle(panel, Area(x + 0.01, z0, x + 0.49, z1), cv::Scalar(shade(random)), cv::FILLED);
      const double handle_z = z0 < 1 ? z1 - 0.08 : z0 + 0.08;
      cv::rectangle(panel, Area(x + 0.2, handle_z - 0.01, x + 0.3, handle_z + 0.01),
                    cv::Scalar(100), cv::FILLED);
    }
  }
  return panel;
}

cv::Mat OfficeTextures::Linoleum(double metres, std::uint64_t seed) {
  const int size = Texels(metres) / 2;  // a floor is seen from at least 1.2 m: half resolution
  cv::Mat floor = Uneven(cv::Size(size, size), 120, 10, seed);
  std::mt19937_64 random(seed);
  std::uniform_int_distribution<int> position(0, size - 1), grey(60, 200);
  for (int k = 0; k < size * size / 400; ++k) {
    cv::circle(floor, cv::Point(position(random), position(random)), 1, cv::Scalar(grey(random)),
               cv::FILLED);
  }
  cv::rectangle(floor, cv::Rect(0, 0, size, size), cv::Scalar(95), 2);  // seams
  return floor;
}

cv::Mat OfficeTextures::CeilingTile(double metres, std::uint64_t seed) {
  const int size = Texels(metres) / 2;
  cv::Mat tile = Uneven(cv::Size(size, size), 215, 4, seed);
  cv::rectangle(tile, cv::Rect(0, 0, size, size), cv::Scalar(165), 3);  // the grid's T-bars
  return tile;
}

cv::Mat OfficeTextures::CeilingLight(double metres) {
  const int size = Texels(metres) / 2;
  cv::Mat light(size, size, CV_8U, cv::Scalar(255));
  cv::rectangle(light, cv::Rect(0, 0, size, size), cv::Scalar(165), 3);
  cv::rectangle(light, cv::Rect(6, 6, size - 12, size - 12), cv::Scalar(200), 4);
  return light;
}

cv::Mat OfficeTextures::Wood(const cv::Size2d& size, std::uint64_t seed) {
  const cv::Size texels(Texels(size.width), Texels(size.height));
  cv::Mat grain = Uneven(cv::Size(texels.width / 8 + 1, texels.height), 140, 25, seed);
  cv::resize(grain, grain, texels, 0, 0, cv::INTER_LINEAR);
  return grain;
}

cv::Mat OfficeTextures::Leaves(const cv::Size2d& size, std::uint64_t seed) {
  const cv::Size texels(Texels(size.width), Texels(size.height));
  cv::Mat leaves(texels, CV_8U, cv::Scalar(55));
  std::mt19937_64 random(seed);
  std::uniform_int_distribution<int> x(0, texels.width), y(0, texels.height), grey(30, 120),
      angle(0, 179);
  for (int k = 0; k < texels.area() / 600; ++k) {
    cv::ellipse(leaves, cv::Point(x(random), y(random)), cv::Size(14, 5), angle(random), 0, 360,
                cv::Scalar(grey(random)), cv::FILLED, cv::LINE_AA);
  }
  return leaves;
}

cv::Mat OfficeTextures::Appliance(const cv::Size2d& size) {
  const cv::Size texels(Texels(size.width), Texels(size.height));
  cv::Mat front(texels, CV_8U, cv::Scalar(225));
  const int split = texels.height * 35 / 100;
  cv::line(front, cv::Point(0, split), cv::Point(texels.width, split), cv::Scalar(140), 3);
  cv::rectangle(front,
                cv::Rect(texels.width / 10, split - Texels(0.3), Texels(0.025), Texels(0.25)),
                cv::Scalar(120), cv::FILLED);
  cv::rectangle(front,
                cv::Rect(texels.width / 10, split + Texels(0.05), Texels(0.025), Texels(0.35)),
                cv::Scalar(120), cv::FILLED);
  return front;
}

}  // namespace stereo_fabmap_slam::datasets
