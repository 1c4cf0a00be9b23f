#include "stereo_fabmap_slam/evaluation/trajectory_io.h"

#include <cmath>
#include <cstdio>
#include <fstream>
#include <memory>

#include "stereo_fabmap_slam/io/csv_reader.h"

namespace stereo_fabmap_slam::evaluation {
namespace {

using io::FileError;
using io::ParseDouble;
using io::ParseInt64;
using io::ReadDelimitedText;
using io::Separator;
using io::TextRow;

std::vector<double> ParseNumbers(const TextRow& row, const std::string& path, std::size_t first,
                                 std::size_t count) {
  std::vector<double> values;
  for (std::size_t i = first; i < first + count; ++i) {
    values.push_back(ParseDouble(row.fields[i], path, row.line_number));
  }
  return values;
}

void RequireFieldCount(const TextRow& row, const std::string& path,
                       std::initializer_list<std::size_t> accepted, const char* layout) {
  for (const std::size_t count : accepted) {
    if (row.fields.size() == count) return;
  }
  throw FileError(path, row.line_number,
                  "expected " + std::string(layout) + ", found " +
                      std::to_string(row.fields.size()) + " fields");
}

Eigen::Quaterniond CheckedQuaternion(double w, double x, double y, double z,
                                     const std::string& path, std::size_t line) {
  const Eigen::Quaterniond q(w, x, y, z);
  if (!(std::abs(q.norm() - 1.0) < 1e-2)) {
    throw FileError(path, line, "quaternion is not of unit length");
  }
  return q;
}

void RequireIncreasingTime(const Trajectory& trajectory, const std::string& path,
                           std::size_t line) {
  const std::size_t n = trajectory.size();
  if (n >= 2 && !(trajectory[n - 1].timestamp > trajectory[n - 2].timestamp)) {
    throw FileError(path, line, "timestamps must increase");
  }
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

}  // namespace

Trajectory ReadTumTrajectory(const std::string& path) {
  Trajectory trajectory;
  for (const TextRow& row : ReadDelimitedText(path, Separator::kWhitespace)) {
    RequireFieldCount(row, path, {8}, "8 fields 't x y z qx qy qz qw'");
    const std::vector<double> v = ParseNumbers(row, path, 0, 8);
    const Eigen::Quaterniond q = CheckedQuaternion(v[7], v[4], v[5], v[6], path, row.line_number);
    trajectory.push_back({v[0], PoseFromTranslationQuaternion({v[1], v[2], v[3]}, q)});
    RequireIncreasingTime(trajectory, path, row.line_number);
  }
  return trajectory;
}

Trajectory ReadEurocTrajectory(const std::string& path) {
  Trajectory trajectory;
  for (const TextRow& row : ReadDelimitedText(path, Separator::kComma)) {
    RequireFieldCount(row, path, {8, 17},
                      "8 or 17 fields 'timestamp [ns], x, y, z, qw, qx, qy, qz[, ...]'");
    const std::int64_t stamp_ns = ParseInt64(row.fields[0], path, row.line_number);
    const std::vector<double> v = ParseNumbers(row, path, 1, 7);
    const Eigen::Quaterniond q = CheckedQuaternion(v[3], v[4], v[5], v[6], path, row.line_number);
    trajectory.push_back({static_cast<double>(stamp_ns) * 1e-9,
                          PoseFromTranslationQuaternion({v[0], v[1], v[2]}, q)});
    RequireIncreasingTime(trajectory, path, row.line_number);
  }
  return trajectory;
}

Trajectory ReadKittiTrajectory(const std::string& path) {
  Trajectory trajectory;
  for (const TextRow& row : ReadDelimitedText(path, Separator::kWhitespace)) {
    RequireFieldCount(row, path, {12}, "12 numbers (3x4 pose, row-major)");
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
  const TextRow& first = rows.front();
  if (first.fields.front().find(',') != std::string::npos) return TrajectoryFormat::kEuroc;
  if (first.fields.size() == 12) return TrajectoryFormat::kKitti;
  if (first.fields.size() == 8) return TrajectoryFormat::kTum;
  throw FileError(path, first.line_number,
                  "cannot tell the format: expected TUM (8 fields), KITTI (12) or EuRoC CSV");
}

Trajectory ReadTrajectory(const std::string& path, TrajectoryFormat format) {
  switch (format) {
    case TrajectoryFormat::kTum:
      return ReadTumTrajectory(path);
    case TrajectoryFormat::kEuroc:
      return ReadEurocTrajectory(path);
    case TrajectoryFormat::kKitti:
      return ReadKittiTrajectory(path);
  }
  throw FileError(path, 0, "unknown trajectory format");
}

Trajectory ReadTrajectory(const std::string& path) {
  return ReadTrajectory(path, DetectTrajectoryFormat(path));
}

}  // namespace stereo_fabmap_slam::evaluation
