#include "stereo_fabmap_slam/evaluation/homography_transfer.h"

#include <cmath>
#include <filesystem>
#include <fstream>

#include "stereo_fabmap_slam/io/input_error.h"

namespace stereo_fabmap_slam::evaluation {
namespace {

bool IsFileStorage(const std::string& path) {
  const std::string extension = std::filesystem::path(path).extension().string();
  return extension == ".xml" || extension == ".yml" || extension == ".yaml" || extension == ".json";
}

cv::Matx33d ReadFileStorageHomography(const std::string& path) {
  cv::Mat matrix;
  try {
    const cv::FileStorage storage(path, cv::FileStorage::READ);
    if (!storage.isOpened()) throw io::FileError(path, 0, "cannot open");
    for (const cv::FileNode& node : storage.root()) {
      if (node.isMap() || node.isSeq()) {
        node >> matrix;
        if (!matrix.empty()) break;
      }
    }
  } catch (const cv::Exception& error) {
    throw io::FileError(path, 0, error.what());
  }
  if (matrix.rows != 3 || matrix.cols != 3 || matrix.channels() != 1) {
    throw io::FileError(path, 0, "no 3x3 matrix in it");
  }
  cv::Mat as_double;
  matrix.convertTo(as_double, CV_64F);
  return cv::Matx33d(as_double);
}

cv::Matx33d ReadTextHomography(const std::string& path) {
  std::ifstream file(path);
  if (!file) throw io::FileError(path, 0, "cannot open");
  cv::Matx33d H;
  for (int i = 0; i < 9; ++i) {
    if (!(file >> H.val[i])) throw io::FileError(path, 0, "expected 9 numbers (3x3, row-major)");
  }
  std::string extra;
  if (file >> extra) throw io::FileError(path, 0, "more than 9 numbers: '" + extra + "'");
  return H;
}

}  // namespace

HomographyTransfer::HomographyTransfer(const cv::Matx33d& H, const cv::Size& test_size)
    : H_(H), test_size_(test_size) {}

std::optional<cv::Point2f> HomographyTransfer::Transfer(std::size_t /*index*/,
                                                        const cv::Point2f& point) const {
  const cv::Vec3d x = H_ * cv::Vec3d(point.x, point.y, 1.0);
  if (!(x[2] > 0)) return std::nullopt;  // behind the camera or at infinity
  const double u = x[0] / x[2], v = x[1] / x[2];
  if (!(u >= 0 && v >= 0 && u < test_size_.width && v < test_size_.height)) return std::nullopt;
  return cv::Point2f(static_cast<float>(u), static_cast<float>(v));
}

cv::Matx33d ReadHomography(const std::string& path) {
  const cv::Matx33d H =
      IsFileStorage(path) ? ReadFileStorageHomography(path) : ReadTextHomography(path);
  for (const double value : H.val) {
    if (!std::isfinite(value)) throw io::FileError(path, 0, "a value is not finite");
  }
  if (std::abs(cv::determinant(H)) < 1e-12) throw io::FileError(path, 0, "singular homography");
  return H;
}

}  // namespace stereo_fabmap_slam::evaluation
