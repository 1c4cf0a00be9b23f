#include "stereo_fabmap_slam/io/csv_reader.h"

#include <cerrno>
#include <cstdlib>
#include <fstream>
#include <sstream>

namespace stereo_fabmap_slam::io {
namespace {

std::string Trim(const std::string& text) {
  const auto first = text.find_first_not_of(" \t\r\n");
  if (first == std::string::npos) return "";
  const auto last = text.find_last_not_of(" \t\r\n");
  return text.substr(first, last - first + 1);
}

std::vector<std::string> Split(const std::string& line, Separator separator) {
  std::vector<std::string> fields;
  if (separator == Separator::kWhitespace) {
    std::istringstream stream(line);
    std::string field;
    while (stream >> field) fields.push_back(field);
    return fields;
  }
  std::size_t start = 0;
  while (true) {
    const std::size_t comma = line.find(',', start);
    fields.push_back(Trim(line.substr(start, comma - start)));
    if (comma == std::string::npos) break;
    start = comma + 1;
  }
  return fields;
}

}  // namespace

std::vector<TextRow> ReadDelimitedText(const std::string& path, Separator separator) {
  std::ifstream file(path);
  if (!file) throw FileError(path, 0, "cannot open file");
  std::vector<TextRow> rows;
  std::string line;
  std::size_t line_number = 0;
  while (std::getline(file, line)) {
    ++line_number;
    const std::string trimmed = Trim(line);
    if (trimmed.empty() || trimmed.front() == '#') continue;
    rows.push_back({line_number, Split(trimmed, separator)});
  }
  if (file.bad()) throw FileError(path, line_number, "read error");
  return rows;
}

double ParseDouble(const std::string& field, const std::string& path, std::size_t line) {
  errno = 0;
  char* end = nullptr;
  const double value = std::strtod(field.c_str(), &end);
  if (field.empty() || end != field.c_str() + field.size() || errno == ERANGE) {
    throw FileError(path, line, "expected a number, found '" + field + "'");
  }
  return value;
}

std::int64_t ParseInt64(const std::string& field, const std::string& path, std::size_t line) {
  errno = 0;
  char* end = nullptr;
  const long long value = std::strtoll(field.c_str(), &end, 10);
  if (field.empty() || end != field.c_str() + field.size() || errno == ERANGE) {
    throw FileError(path, line, "expected an integer, found '" + field + "'");
  }
  return static_cast<std::int64_t>(value);
}

}  // namespace stereo_fabmap_slam::io
