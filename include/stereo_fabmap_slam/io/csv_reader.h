#pragma once

#include <cstdint>
#include <stdexcept>
#include <string>
#include <vector>

namespace stereo_fabmap_slam::io {

// Bad input in a file, with the file and line it came from in the message.
class InputError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// Builds "path:line: message" (line 0 means the file as a whole).
InputError FileError(const std::string& path, std::size_t line, const std::string& message);

// One non-blank, non-comment line of a delimited text file, split into trimmed fields.
struct TextRow {
  std::size_t line_number = 0;  // 1-based, as an editor shows it
  std::vector<std::string> fields;
};

enum class Separator { kComma, kWhitespace };

// Reads every data line of a text file: lines starting with '#' and blank lines are skipped.
// Throws InputError if the file cannot be opened.
std::vector<TextRow> ReadDelimitedText(const std::string& path, Separator separator);

// Field parsers that throw InputError naming the file, line and offending text.
double ParseDouble(const std::string& field, const std::string& path, std::size_t line);
std::int64_t ParseInt64(const std::string& field, const std::string& path, std::size_t line);

}  // namespace stereo_fabmap_slam::io
