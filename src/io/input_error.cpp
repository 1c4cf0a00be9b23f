#include "stereo_fabmap_slam/io/input_error.h"

namespace stereo_fabmap_slam::io {

InputError FileError(const std::string& path, std::size_t line, const std::string& message) {
  if (line == 0) return InputError(path + ": " + message);
  return InputError(path + ":" + std::to_string(line) + ": " + message);
}

}  // namespace stereo_fabmap_slam::io
