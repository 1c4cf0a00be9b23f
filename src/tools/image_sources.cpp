#include "image_sources.h"

#include <algorithm>
#include <filesystem>
#include <stdexcept>

#include "stereo_fabmap_slam/datasets/euroc_sequence.h"

namespace stereo_fabmap_slam::tools {

std::vector<ImageSource> ListImages(const std::string& source, int every) {
  namespace fs = std::filesystem;
  std::vector<ImageSource> images;
  const std::size_t step = static_cast<std::size_t>(std::max(every, 1));
  if (fs::is_directory(source + "/mav0") || fs::is_directory(source + "/cam0")) {
    const datasets::EurocSequence sequence = datasets::EurocSequence::Open(source);
    for (std::size_t i = 0; i < sequence.size(); i += step) {
      images.push_back({sequence.frames()[i].left_path, sequence.frames()[i].timestamp_ns * 1e-9});
    }
    if (images.empty()) throw std::runtime_error(source + ": the sequence has no images");
    return images;
  }
  if (!fs::is_directory(source)) throw std::runtime_error(source + ": no such folder");
  std::vector<std::string> paths;
  for (const auto& entry : fs::directory_iterator(source)) {
    const std::string extension = entry.path().extension().string();
    if (extension == ".png" || extension == ".jpg" || extension == ".jpeg")
      paths.push_back(entry.path().string());
  }
  std::sort(paths.begin(), paths.end());
  for (std::size_t i = 0; i < paths.size(); i += step)
    images.push_back({paths[i], static_cast<double>(i)});
  if (images.empty()) throw std::runtime_error(source + ": no images (*.png, *.jpg, *.jpeg)");
  return images;
}

}  // namespace stereo_fabmap_slam::tools
