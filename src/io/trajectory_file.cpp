#include "stereo_fabmap_slam/io/trajectory_file.h"

#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <memory>

#include "stereo_fabmap_slam/io/csv_reader.h"

namespace stereo_fabmap_slam::io {
namespace {

// Finite numbers: NaN or infinity in a trajectory cannot be meant.
std::vector<double> ParseNumbers(const TextRow& row, const std::string& path, std::size_t first,
                                 std::size_t count) {
  std::vector<double> values;
  for (std::size_t i = first; i < first + count; ++i) {
    values.push_back(ParseDouble(row.fields[i], path, row.line_number));
    if (!std::isfinite(values.back())) {
      throw FileError(path, row.line_number, "'" + row.fields[i] + "' is not a finite number");
    }
  }
  return values;
}

void RequireFieldCount(const TextRow& row, const std::string& path, std::size_t at_least,
                       const char* layout) {
  if (row.fields.size() >= at_least) return;
  throw FileError(path, row.line_number,
                  "expected " + std::string(layout) + ", found " +
                      std::to_string(row.fields.size()) + " fields");
}

// Normalised, as evo does; only a quaternion of (nearly) zero length has no rotation to mean.
Eigen::Quaterniond CheckedQuaternion(double w, double x, double y, double z,
                                     const std::string& path, std::size_t line) {
  const Eigen::Quaterniond q(w, x, y, z);
  if (!(q.norm() > 1e-6)) throw FileError(path, line, "quaternion of zero length");
  return q.normalized();
}

// A first row whose first field is not a number is a header (EuRoC and evo CSVs without '#').
bool IsHeader(const TextRow& row) {
  const std::string& field = row.fields.front();
  char* end = nullptr;
  std::strtod(field.c_str(), &end);
  return field.empty() || end == field.c_str();
}

void NoteStamp(const Trajectory& trajectory, TrajectoryFileNotes* notes) {
  const std::size_t n = trajectory.size();
  if (notes == nullptr || n < 2) return;
  if (trajectory[n - 1].timestamp == trajectory[n - 2].timestamp) ++notes->repeated_stamps;
  if (trajectory[n - 1].timestamp < trajectory[n - 2].timestamp) ++notes->unordered_stamps;
}

// A timestamp in nanoseconds: an integer, or a number with an exponent or decimals (rounded to
// the nanosecond; a double holds 1e18 to within 256 ns).
double ParseNanosecondStamp(const std::string& field, const std::string& path, std::size_t line) {
  char* end = nullptr;
  errno = 0;
  const long long whole = std::strtoll(field.c_str(), &end, 10);
  if (!field.empty() && end == field.c_str() + field.size() && errno != ERANGE) {
    return static_cast<double>(whole) * 1e-9;
  }
  const double value = ParseDouble(field, path, line);
  if (!std::isfinite(value)) throw FileError(path, line, "'" + field + "' is not a finite number");
  return std::round(value) * 1e-9;
}

struct FileCloser {
  void operator()(std::FILE* file) const { std::fclose(file); }
};
using File = std::unique_ptr<std::FILE, FileCloser>;

File OpenForWriting(const std::string& path) {
  File file(std::fopen(path.c_str(), "w"));
  if (!file) throw FileError(path, 0, "cannot open file for writing");
  return file;
}

void FinishWriting(File file, const std::string& path) {
  if (std::ferror(file.get()) || std::fclose(file.release()) != 0) {
    throw FileError(path, 0, "write error");
  }
}

// The data rows of a trajectory file: a header row first is dropped (and noted).
std::vector<TextRow> PoseRows(const std::string& path, Separator separator,
                              TrajectoryFileNotes* notes) {
  std::vector<TextRow> rows = ReadDelimitedText(path, separator);
  if (!rows.empty() && IsHeader(rows.front())) {
    rows.erase(rows.begin());
    if (notes != nullptr) notes->header_skipped = true;
  }
  return rows;
}

}  // namespace

Trajectory ReadTumTrajectory(const std::string& path, TrajectoryFileNotes* notes) {
  Trajectory trajectory;
  for (const TextRow& row : PoseRows(path, Separator::kWhitespace, notes)) {
    RequireFieldCount(row, path, 8, "8 fields 't x y z qx qy qz qw'");
    const std::vector<double> v = ParseNumbers(row, path, 0, 8);
    const Eigen::Quaterniond q = CheckedQuaternion(v[7], v[4], v[5], v[6], path, row.line_number);
    trajectory.push_back({v[0], PoseFromTranslationQuaternion({v[1], v[2], v[3]}, q)});
    NoteStamp(trajectory, notes);
  }
  return trajectory;
}

Trajectory ReadEurocTrajectory(const std::string& path, TrajectoryFileNotes* notes) {
  Trajectory trajectory;
  for (const TextRow& row : PoseRows(path, Separator::kComma, notes)) {
    RequireFieldCount(row, path, 8, "8 fields 'timestamp [ns], x, y, z, qw, qx, qy, qz[, ...]'");
    const double stamp = ParseNanosecondStamp(row.fields[0], path, row.line_number);
    const std::vector<double> v = ParseNumbers(row, path, 1, 7);
    const Eigen::Quaterniond q = CheckedQuaternion(v[3], v[4], v[5], v[6], path, row.line_number);
    trajectory.push_back({stamp, PoseFromTranslationQuaternion({v[0], v[1], v[2]}, q)});
    NoteStamp(trajectory, notes);
  }
  return trajectory;
}

Trajectory ReadKittiTrajectory(const std::string& path) {
  Trajectory trajectory;
  for (const TextRow& row : ReadDelimitedText(path, Separator::kWhitespace)) {
    if (row.fields.size() != 12) {
      throw FileError(
          path, row.line_number,
          "expected 12 numbers (3x4 pose, row-major), found " + std::to_string(row.fields.size()));
    }
    const std::vector<double> v = ParseNumbers(row, path, 0, 12);
    Eigen::Matrix3d rotation;
    rotation << v[0], v[1], v[2], v[4], v[5], v[6], v[8], v[9], v[10];
    if ((rotation.transpose() * rotation - Eigen::Matrix3d::Identity()).norm() > 1e-3) {
      throw FileError(path, row.line_number, "rotation part is not orthonormal");
    }
    const Eigen::Quaterniond q(rotation);
    trajectory.push_back({static_cast<double>(trajectory.size()),
                          PoseFromTranslationQuaternion({v[3], v[7], v[11]}, q)});
  }
  return trajectory;
}

void WriteTumTrajectory(const Trajectory& trajectory, const std::string& path) {
  File file = OpenForWriting(path);
  std::fprintf(file.get(), "# timestamp tx ty tz qx qy qz qw\n");
  for (const StampedPose& p : trajectory) {
    const Eigen::Quaterniond q(p.pose.linear());
    const Eigen::Vector3d& t = p.pose.translation();
    std::fprintf(file.get(), "%.9f %.9f %.9f %.9f %.9f %.9f %.9f %.9f\n", p.timestamp, t.x(), t.y(),
                 t.z(), q.x(), q.y(), q.z(), q.w());
  }
  FinishWriting(std::move(file), path);
}

void WriteEurocTrajectory(const Trajectory& trajectory, const std::string& path) {
  File file = OpenForWriting(path);
  std::fprintf(file.get(),
               "#timestamp [ns], p_RS_R_x [m], p_RS_R_y [m], p_RS_R_z [m], q_RS_w [], q_RS_x [], "
               "q_RS_y [], q_RS_z []\n");
  for (const StampedPose& p : trajectory) {
    const Eigen::Quaterniond q(p.pose.linear());
    const Eigen::Vector3d& t = p.pose.translation();
    std::fprintf(file.get(), "%lld,%.9f,%.9f,%.9f,%.9f,%.9f,%.9f,%.9f\n",
                 static_cast<long long>(std::llround(p.timestamp * 1e9)), t.x(), t.y(), t.z(),
                 q.w(), q.x(), q.y(), q.z());
  }
  FinishWriting(std::move(file), path);
}

void WriteKittiTrajectory(const Trajectory& trajectory, const std::string& path) {
  File file = OpenForWriting(path);
  for (const StampedPose& p : trajectory) {
    const Eigen::Matrix<double, 3, 4> m = p.pose.matrix().topRows<3>();
    for (int r = 0; r < 3; ++r) {
      for (int c = 0; c < 4; ++c) {
        std::fprintf(file.get(), (r == 2 && c == 3) ? "%.9e\n" : "%.9e ", m(r, c));
      }
    }
  }
  FinishWriting(std::move(file), path);
}

TrajectoryFormat DetectTrajectoryFormat(const std::string& path) {
  if (path.size() >= 4 && path.compare(path.size() - 4, 4, ".csv") == 0) {
    return TrajectoryFormat::kEuroc;
  }
  const std::vector<TextRow> rows = ReadDelimitedText(path, Separator::kWhitespace);
  if (rows.empty()) throw FileError(path, 0, "no poses in file");
  // The first row of numbers (a header row may come first).
  const TextRow& first = rows.size() > 1 && IsHeader(rows.front()) ? rows[1] : rows.front();
  if (first.fields.front().find(',') != std::string::npos) return TrajectoryFormat::kEuroc;
  if (first.fields.size() == 12) return TrajectoryFormat::kKitti;
  if (first.fields.size() >= 8) return TrajectoryFormat::kTum;
  throw FileError(path, first.line_number,
                  "cannot tell the format: expected TUM (8 fields), KITTI (12) or EuRoC CSV");
}

Trajectory ReadTrajectory(const std::string& path, TrajectoryFormat format,
                          TrajectoryFileNotes* notes) {
  switch (format) {
    case TrajectoryFormat::kTum:
      return ReadTumTrajectory(path, notes);
    case TrajectoryFormat::kEuroc:
      return ReadEurocTrajectory(path, notes);
    case TrajectoryFormat::kKitti:
      return ReadKittiTrajectory(path);
  }
  throw FileError(path, 0, "unknown trajectory format");
}

Trajectory ReadTrajectory(const std::string& path, TrajectoryFileNotes* notes) {
  return ReadTrajectory(path, DetectTrajectoryFormat(path), notes);
}

}  // namespace stereo_fabmap_slam::io
