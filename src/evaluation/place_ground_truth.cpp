#include "stereo_fabmap_slam/evaluation/place_ground_truth.h"

#include <algorithm>
#include <filesystem>
#include <stdexcept>
#include <string>

#include <opencv2/imgcodecs.hpp>

#include "stereo_fabmap_slam/evaluation/relocalization_recall.h"
#include "stereo_fabmap_slam/io/csv_reader.h"
#include "stereo_fabmap_slam/io/input_error.h"

namespace stereo_fabmap_slam::evaluation {
namespace {

bool IsTextFile(const std::string& path) {
  std::string extension = std::filesystem::path(path).extension().string();
  std::transform(extension.begin(), extension.end(), extension.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return extension == ".csv" || extension == ".txt";
}

cv::Mat ReadTextMatrix(const std::string& path) {
  // Commas or blanks: benchmarks ship both. A line with a comma is split at commas.
  std::vector<io::TextRow> rows = io::ReadDelimitedText(path, io::Separator::kComma);
  if (!rows.empty() && rows.front().fields.size() == 1)
    rows = io::ReadDelimitedText(path, io::Separator::kWhitespace);
  const int n = static_cast<int>(rows.size());
  if (n == 0) throw io::FileError(path, 0, "no rows in the ground-truth matrix");
  cv::Mat same(n, n, CV_8U);
  for (int i = 0; i < n; ++i) {
    const io::TextRow& row = rows[static_cast<std::size_t>(i)];
    if (static_cast<int>(row.fields.size()) != n) {
      throw io::FileError(path, row.line_number,
                          std::to_string(row.fields.size()) + " numbers in a row of an " +
                              std::to_string(n) + " x " + std::to_string(n) + " matrix");
    }
    for (int j = 0; j < n; ++j) {
      same.at<unsigned char>(i, j) =
          io::ParseDouble(row.fields[static_cast<std::size_t>(j)], path, row.line_number) != 0.0;
    }
  }
  return same;
}

cv::Mat ReadImageMatrix(const std::string& path) {
  const cv::Mat image = cv::imread(path, cv::IMREAD_UNCHANGED);
  if (image.empty()) throw io::FileError(path, 0, "cannot read the ground-truth image");
  if (image.channels() != 1)
    throw io::FileError(path, 0, "the ground-truth image must have one (grey) channel");
  if (image.rows != image.cols) {
    throw io::FileError(path, 0,
                        "the ground-truth image is " + std::to_string(image.cols) + " x " +
                            std::to_string(image.rows) + " pixels, not square");
  }
  cv::Mat same;
  cv::compare(image, 0, same, cv::CMP_NE);  // 255 where non-zero, any depth
  return same;
}

}  // namespace

PlaceGroundTruth::PlaceGroundTruth(const cv::Mat& same) {
  if (same.rows != same.cols || same.type() != CV_8U)
    throw std::invalid_argument("PlaceGroundTruth: the matrix must be square and CV_8U");
  cv::Mat nonzero, transposed;
  cv::compare(same, 0, nonzero, cv::CMP_NE);
  cv::transpose(nonzero, transposed);
  cv::bitwise_or(nonzero, transposed, same_);
  same_ /= 255;
}

PlaceGroundTruth PlaceGroundTruth::Load(const std::string& path) {
  return PlaceGroundTruth(IsTextFile(path) ? ReadTextMatrix(path) : ReadImageMatrix(path));
}

PlaceGroundTruth PlaceGroundTruth::FromPoses(
    const std::vector<std::vector<Eigen::Vector3d>>& points,
    const std::vector<std::optional<Eigen::Isometry3d>>& T_world_camera,
    const geometry::StereoCamera& camera, double tau) {
  PlaceRelevance relevance;
  relevance.tau = tau;
  return FromPoses(points, T_world_camera, camera, relevance);
}

PlaceGroundTruth PlaceGroundTruth::FromPoses(
    const std::vector<std::vector<Eigen::Vector3d>>& points,
    const std::vector<std::optional<Eigen::Isometry3d>>& T_world_camera,
    const geometry::StereoCamera& camera, const PlaceRelevance& relevance) {
  if (points.size() != T_world_camera.size())
    throw std::invalid_argument("PlaceGroundTruth: one point list per pose is needed");
  const double tau = relevance.tau;
  if (!(tau > 0.0 && tau <= 1.0)) throw std::invalid_argument("PlaceGroundTruth: tau in (0, 1]");
  if (!(relevance.max_distance > 0.0))
    throw std::invalid_argument("PlaceGroundTruth: the largest distance must be > 0");
  const int n = static_cast<int>(points.size());
  cv::Mat same = cv::Mat::eye(n, n, CV_8U);
  for (int i = 0; i < n; ++i) {
    if (!T_world_camera[i]) continue;
    for (int j = i + 1; j < n; ++j) {
      if (!T_world_camera[j]) continue;
      const Eigen::Isometry3d T_j_i = T_world_camera[j]->inverse() * *T_world_camera[i];
      if (T_j_i.translation().norm() > relevance.max_distance) continue;
      const bool i_in_j = VisibleFraction(points[i], T_j_i, camera) >= tau;
      const bool j_in_i = VisibleFraction(points[j], T_j_i.inverse(), camera) >= tau;
      same.at<unsigned char>(i, j) = relevance.mutual ? i_in_j && j_in_i : i_in_j || j_in_i;
    }
  }
  return PlaceGroundTruth(same);
}

PlaceGroundTruth PlaceGroundTruth::Subset(const std::vector<int>& indices) const {
  const int n = static_cast<int>(indices.size());
  cv::Mat same(n, n, CV_8U);
  for (int a = 0; a < n; ++a) {
    for (int b = 0; b < n; ++b) {
      const int i = indices[a], j = indices[b];
      if (i < 0 || j < 0 || i >= size() || j >= size())
        throw std::out_of_range("PlaceGroundTruth::Subset: frame outside the matrix");
      same.at<unsigned char>(a, b) = same_.at<unsigned char>(i, j);
    }
  }
  return PlaceGroundTruth(same);
}

long PlaceGroundTruth::SamePairs() const {
  return (static_cast<long>(cv::countNonZero(same_)) - cv::countNonZero(same_.diag())) / 2;
}

}  // namespace stereo_fabmap_slam::evaluation
