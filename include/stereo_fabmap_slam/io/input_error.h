#pragma once

#include <cstddef>
#include <stdexcept>
#include <string>

namespace stereo_fabmap_slam::io {

// Bad input in a file, with the file and line it came from in the message.
class InputError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// Builds "path:line: message" (line 0 means the file as a whole).
InputError FileError(const std::string& path, std::size_t line, const std::string& message);

}  // namespace stereo_fabmap_slam::io
