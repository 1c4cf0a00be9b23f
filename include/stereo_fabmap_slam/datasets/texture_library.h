#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include <opencv2/core.hpp>

namespace stereo_fabmap_slam::datasets {

// A grey-level texture with its mip pyramid (each level half the size of the one before), so
// that a renderer can sample distant surfaces without aliasing.
struct Texture {
  std::vector<cv::Mat> levels;  // CV_8UC1, level 0 full size
  std::vector<float> scales;    // level size / full size, per level
  std::string name;             // file name, or "procedural <seed>"
};

// Real photographs from a folder (the Debian package opencv-doc installs about a hundred), kept
// when they are large and textured enough to carry features, plus procedural textures
// (multi-scale value noise) for surfaces a photo does not fit (floor, ceiling).
class TextureLibrary {
 public:
  // Photos: *.jpg and *.png of at least 400 x 300 px whose mean absolute Laplacian (texture
  // strength) is at least `min_texture`, in file name order, at most two of a numbered series
  // (name01, name02, ...). Throws std::runtime_error if the folder yields no photo.
  static TextureLibrary Load(const std::string& photo_folder, double min_texture = 6.0);

  const std::vector<Texture>& photos() const { return photos_; }
  // A procedural texture of size x size texels, the same for the same seed.
  static Texture Procedural(int size, std::uint64_t seed);
  static Texture FromImage(const cv::Mat& grey, const std::string& name);

 private:
  std::vector<Texture> photos_;
};

}  // namespace stereo_fabmap_slam::datasets
