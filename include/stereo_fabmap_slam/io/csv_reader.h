#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "stereo_fabmap_slam/io/input_error.h"

namespace stereo_fabmap_slam::io {

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
