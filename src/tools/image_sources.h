#pragma once

#include <string>
#include <vector>

namespace stereo_fabmap_slam::tools {

struct ImageSource {
  std::string path;
  double timestamp;  // [s] for a sequence; the index in the folder otherwise
};

// Every `every`-th image of a EuRoC ASL sequence (its left camera) or of a folder of *.png and
// *.jpg files (in name order). Throws std::runtime_error for a missing folder or one with no
// images: a source with nothing in it is a mistake, not an empty result.
std::vector<ImageSource> ListImages(const std::string& source, int every);

}  // namespace stereo_fabmap_slam::tools
