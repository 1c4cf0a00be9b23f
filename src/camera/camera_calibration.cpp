#include "stereo_fabmap_slam/camera/camera_calibration.h"

#include <cmath>
#include <fstream>
#include <iomanip>
#include <stdexcept>

#include "stereo_fabmap_slam/io/input_error.h"

namespace stereo_fabmap_slam::camera {
namespace {

Eigen::Isometry3d ParseTransform(const io::YamlFile& file, const YAML::Node& node,
                                 const std::string& key) {
  const YAML::Node child = file.Child(node, key);
  const std::vector<double> values =
      child.IsMap() ? file.Numbers(child, "data", 16) : file.Numbers(node, key, 16);
  if (child.IsMap() && (file.Number(child, "rows") != 4 || file.Number(child, "cols") != 4)) {
    throw io::FileError(file.source(), child.Mark().line + 1, "'" + key + "' must be 4x4");
  }
  Eigen::Matrix4d matrix;
  for (int r = 0; r < 4; ++r) {
    for (int c = 0; c < 4; ++c) matrix(r, c) = values[4 * r + c];
  }
  const Eigen::Matrix3d rotation = matrix.topLeftCorner<3, 3>();
  const double orthogonality =
      (rotation.transpose() * rotation - Eigen::Matrix3d::Identity()).norm();
  if (orthogonality > 1e-4 || std::abs(rotation.determinant() - 1.0) > 1e-4 ||
      (matrix.row(3) - Eigen::RowVector4d(0, 0, 0, 1)).norm() > 1e-9) {
    throw io::FileError(file.source(), child.Mark().line + 1,
                        "'" + key + "' is not a rigid transform");
  }
  // Re-orthonormalise: files store rotations to about 1e-9, Eigen's Isometry wants exact ones.
  Eigen::Isometry3d transform = Eigen::Isometry3d::Identity();
  transform.linear() = Eigen::Quaterniond(rotation).normalized().toRotationMatrix();
  transform.translation() = matrix.topRightCorner<3, 1>();
  return transform;
}

// One camera in sensor.yaml form, every line prefixed by `indent`.
void WriteCamera(const CameraCalibration& camera, const std::string& comment,
                 const std::string& indent, std::ostream& out) {
  out << std::setprecision(15);
  out << indent << "comment: " << comment << "\n"
      << indent << "T_BS:\n"
      << indent << "  cols: 4\n"
      << indent << "  rows: 4\n"
      << indent << "  data: [";
  const Eigen::Matrix4d T = camera.T_body_camera.matrix();
  for (int i = 0; i < 16; ++i) out << T(i / 4, i % 4) << (i < 15 ? ", " : "]\n");
  out << indent << "rate_hz: " << camera.rate_hz << "\n"
      << indent << "resolution: [" << camera.resolution.width << ", " << camera.resolution.height
      << "]\n"
      << indent << "camera_model: pinhole\n"
      << indent << "intrinsics: [" << camera.fx << ", " << camera.fy << ", " << camera.cx << ", "
      << camera.cy << "]  # fu, fv, cu, cv\n"
      << indent << "distortion_model: radial-tangential\n"
      << indent << "distortion_coefficients: [";
  for (std::size_t i = 0; i < camera.distortion.size(); ++i) {
    out << camera.distortion[i] << (i + 1 < camera.distortion.size() ? ", " : "]\n");
  }
}

}  // namespace

void WriteEurocSensorYaml(const CameraCalibration& camera, const std::string& comment,
                          const std::string& path) {
  std::ofstream out(path);
  out << "# General sensor definitions.\nsensor_type: camera\n";
  WriteCamera(camera, comment, "", out);
  if (!out) throw std::runtime_error("cannot write " + path);
}

void WriteStereoCalibrationYaml(const StereoCalibration& calibration, const std::string& path) {
  std::ofstream out(path);
  out << "# Stereo calibration in sensor.yaml form (left = cam0, right = cam1); T_BS is each "
         "camera's\n"
         "# pose in the body frame.\nleft:\n";
  WriteCamera(calibration.left, "left camera", "  ", out);
  out << "\nright:\n";
  WriteCamera(calibration.right, "right camera", "  ", out);
  if (!calibration.T_body_base.isApprox(Eigen::Isometry3d::Identity(), 1e-12)) {
    out << "\n# The robot base (x forward, y left, z up) in the body frame.\nT_body_base:\n"
        << "  cols: 4\n  rows: 4\n  data: [";
    const Eigen::Matrix4d T = calibration.T_body_base.matrix();
    for (int i = 0; i < 16; ++i) out << T(i / 4, i % 4) << (i < 15 ? ", " : "]\n");
  }
  if (!out) throw std::runtime_error("cannot write " + path);
}

cv::Matx33d CameraCalibration::CameraMatrix() const {
  return cv::Matx33d(fx, 0, cx, 0, fy, cy, 0, 0, 1);
}

void CameraCalibration::Validate() const {
  if (resolution.width <= 0 || resolution.height <= 0) {
    throw std::invalid_argument("camera resolution must be positive");
  }
  if (!(fx > 0) || !(fy > 0)) throw std::invalid_argument("focal lengths must be positive");
  if (!(cx > 0 && cx < resolution.width && cy > 0 && cy < resolution.height)) {
    throw std::invalid_argument("principal point must lie inside the image");
  }
  if (distortion.size() != 4 && distortion.size() != 5) {
    throw std::invalid_argument("radial-tangential distortion needs 4 or 5 coefficients");
  }
}

Eigen::Isometry3d StereoCalibration::T_right_left() const {
  return right.T_body_camera.inverse() * left.T_body_camera;
}

void StereoCalibration::Validate() const {
  left.Validate();
  right.Validate();
  if (left.resolution != right.resolution) {
    throw std::invalid_argument("left and right cameras must have the same resolution");
  }
  if (T_right_left().translation().norm() < 1e-3) {
    throw std::invalid_argument("stereo baseline is below 1 mm: check T_BS of both cameras");
  }
}

CameraCalibration ParseCameraCalibration(const io::YamlFile& file, const YAML::Node& node) {
  CameraCalibration calibration;
  if (file.Has(node, "camera_model") && file.String(node, "camera_model") != "pinhole") {
    throw io::FileError(file.source(), node["camera_model"].Mark().line + 1,
                        "camera_model must be 'pinhole'");
  }
  const std::string model = file.String(node, "distortion_model");
  if (model != "radial-tangential" && model != "radtan" && model != "plumb_bob") {
    throw io::FileError(file.source(), node["distortion_model"].Mark().line + 1,
                        "unsupported distortion_model '" + model +
                            "' (supported: radial-tangential, radtan, plumb_bob)");
  }
  // Each value is checked where it is read, so that an error names its own line.
  const auto fail_at = [&](const char* key, const std::string& message) {
    throw io::FileError(file.source(), node[key].Mark().line + 1, message);
  };
  const std::vector<double> resolution = file.Numbers(node, "resolution", 2);
  calibration.resolution =
      cv::Size(static_cast<int>(resolution[0]), static_cast<int>(resolution[1]));
  if (calibration.resolution.width <= 0 || calibration.resolution.height <= 0) {
    fail_at("resolution", "camera resolution must be positive");
  }
  const std::vector<double> intrinsics = file.Numbers(node, "intrinsics", 4);
  calibration.fx = intrinsics[0];
  calibration.fy = intrinsics[1];
  calibration.cx = intrinsics[2];
  calibration.cy = intrinsics[3];
  if (!(calibration.fx > 0) || !(calibration.fy > 0)) {
    fail_at("intrinsics", "focal lengths must be positive");
  }
  if (!(calibration.cx > 0 && calibration.cx < calibration.resolution.width && calibration.cy > 0 &&
        calibration.cy < calibration.resolution.height)) {
    fail_at("intrinsics", "principal point must lie inside the image");
  }
  calibration.distortion = file.Numbers(node, "distortion_coefficients");
  if (calibration.distortion.size() != 4 && calibration.distortion.size() != 5) {
    fail_at("distortion_coefficients", "radial-tangential distortion needs 4 or 5 coefficients");
  }
  calibration.T_body_camera = ParseTransform(file, node, "T_BS");
  if (file.Has(node, "rate_hz")) calibration.rate_hz = file.Number(node, "rate_hz");
  try {
    calibration.Validate();  // everything above; kept for a change of Validate()
  } catch (const std::invalid_argument& error) {
    throw io::FileError(file.source(), node.Mark().line + 1, error.what());
  }
  return calibration;
}

CameraCalibration ReadEurocSensorYaml(const std::string& path) {
  const io::YamlFile file = io::YamlFile::Load(path);
  return ParseCameraCalibration(file, file.root());
}

StereoCalibration ReadStereoCalibrationYaml(const std::string& path) {
  const io::YamlFile file = io::YamlFile::Load(path);
  StereoCalibration stereo;
  stereo.left = ParseCameraCalibration(file, file.Child(file.root(), "left"));
  stereo.right = ParseCameraCalibration(file, file.Child(file.root(), "right"));
  if (file.Has(file.root(), "T_body_base")) {
    stereo.T_body_base = ParseTransform(file, file.root(), "T_body_base");
  }
  // What only the pair can get wrong, at the right camera's line that disagrees.
  const YAML::Node right = file.Child(file.root(), "right");
  if (stereo.left.resolution != stereo.right.resolution) {
    throw io::FileError(path, right["resolution"].Mark().line + 1,
                        "left and right cameras must have the same resolution");
  }
  try {
    stereo.Validate();
  } catch (const std::invalid_argument& error) {
    throw io::FileError(path, right["T_BS"].Mark().line + 1, error.what());
  }
  return stereo;
}

}  // namespace stereo_fabmap_slam::camera
