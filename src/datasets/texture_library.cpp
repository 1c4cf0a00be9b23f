#include "stereo_fabmap_slam/datasets/texture_library.h"

#include <algorithm>
#include <cctype>
#include <filesystem>
#include <map>
#include <random>
#include <stdexcept>

#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

namespace stereo_fabmap_slam::datasets {

Texture TextureLibrary::FromImage(const cv::Mat& grey, const std::string& name) {
  Texture texture;
  texture.name = name;
  texture.levels.push_back(grey);
  while (texture.levels.back().cols > 8 && texture.levels.back().rows > 8) {
    cv::Mat smaller;
    cv::pyrDown(texture.levels.back(), smaller);
    texture.levels.push_back(smaller);
  }
  for (const cv::Mat& level : texture.levels) {
    texture.scales.push_back(static_cast<float>(level.cols) / static_cast<float>(grey.cols));
  }
  return texture;
}

TextureLibrary TextureLibrary::Load(const std::string& photo_folder, double min_texture) {
  std::vector<std::filesystem::path> files;
  if (std::filesystem::is_directory(photo_folder)) {
    for (const auto& entry : std::filesystem::directory_iterator(photo_folder)) {
      const std::string extension = entry.path().extension().string();
      if (extension == ".jpg" || extension == ".png") files.push_back(entry.path());
    }
  }
  std::sort(files.begin(), files.end());
  // A numbered series (left01.jpg ... left14.jpg: one chessboard, fourteen poses) counts twice
  // at most: a few places may look alike, but not a whole hall of chessboards.
  std::map<std::string, int> series;
  TextureLibrary library;
  for (const std::filesystem::path& file : files) {
    std::string stem = file.stem().string();
    while (!stem.empty() && std::isdigit(static_cast<unsigned char>(stem.back()))) stem.pop_back();
    if (stem.size() < file.stem().string().size() && ++series[stem] > 2) continue;
    const cv::Mat grey = cv::imread(file.string(), cv::IMREAD_GRAYSCALE);
    if (grey.empty() || grey.cols < 400 || grey.rows < 300) continue;
    cv::Mat laplacian;
    cv::Laplacian(grey, laplacian, CV_16S);
    if (cv::mean(cv::abs(laplacian))[0] < min_texture) continue;
    library.photos_.push_back(FromImage(grey, file.filename().string()));
  }
  if (library.photos_.empty()) {
    throw std::runtime_error(
        "no usable photos in " + photo_folder +
        " (install the Debian package opencv-doc, or pass a folder of photos)");
  }
  return library;
}

Texture TextureLibrary::Procedural(int size, std::uint64_t seed) {
  // Value noise over five octaves: random grey levels on ever finer grids, smoothly enlarged and
  // summed, like the blotchy concrete of a floor.
  std::mt19937_64 random(seed);
  cv::Mat sum(size, size, CV_32F, cv::Scalar(0));
  float weight = 1.0f, total = 0.0f;
  for (int cells = 4; cells <= size / 4 && cells <= 256; cells *= 2) {
    cv::Mat grid(cells, cells, CV_32F);
    std::uniform_real_distribution<float> value(0.0f, 255.0f);
    for (int r = 0; r < cells; ++r) {
      for (int c = 0; c < cells; ++c) grid.at<float>(r, c) = value(random);
    }
    cv::Mat enlarged;
    cv::resize(grid, enlarged, cv::Size(size, size), 0, 0, cv::INTER_CUBIC);
    sum += weight * enlarged;
    total += weight;
    weight *= 0.65f;
  }
  cv::Mat grey;
  sum.convertTo(grey, CV_8U, 1.0 / total);
  cv::equalizeHist(grey, grey);  // full contrast, so that corners appear at every scale
  return FromImage(grey, "procedural " + std::to_string(seed));
}

}  // namespace stereo_fabmap_slam::datasets
