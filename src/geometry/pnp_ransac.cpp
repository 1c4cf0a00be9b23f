#include "stereo_fabmap_slam/geometry/pnp_ransac.h"

#include <algorithm>
#include <cmath>
#include <random>

#include <opencv2/calib3d.hpp>
#include <opencv2/core/eigen.hpp>

namespace stereo_fabmap_slam::geometry {
namespace {

int OpenCvFlag(PnpKernel kernel) {
  switch (kernel) {
    case PnpKernel::kIterative:
      return cv::SOLVEPNP_ITERATIVE;
    case PnpKernel::kEpnp:
      return cv::SOLVEPNP_EPNP;
    case PnpKernel::kAp3p:
      return cv::SOLVEPNP_AP3P;
    case PnpKernel::kP3p:
      return cv::SOLVEPNP_P3P;
    case PnpKernel::kSqpnp:
      return cv::SOLVEPNP_SQPNP;
    case PnpKernel::kUmeyama:
      break;
  }
  return cv::SOLVEPNP_ITERATIVE;
}

void ToOpenCv(const Eigen::Isometry3d& T, cv::Mat* rotation_vector, cv::Mat* translation) {
  const Eigen::AngleAxisd rotation(T.linear());
  const Eigen::Vector3d axis = rotation.angle() * rotation.axis();
  *rotation_vector = (cv::Mat_<double>(3, 1) << axis.x(), axis.y(), axis.z());
  *translation =
      (cv::Mat_<double>(3, 1) << T.translation().x(), T.translation().y(), T.translation().z());
}

Eigen::Isometry3d FromOpenCv(const cv::Mat& rotation_vector, const cv::Mat& translation) {
  cv::Mat rotation;
  cv::Rodrigues(rotation_vector, rotation);
  Eigen::Matrix3d r;
  Eigen::Vector3d t;
  cv::cv2eigen(rotation, r);
  cv::cv2eigen(translation, t);
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear() = r;
  T.translation() = t;
  return T;
}

double PixelReprojectionError(const PnpCorrespondence& c, const Eigen::Isometry3d& T_camera_world,
                              const geometry::StereoCamera& camera) {
  const Eigen::Vector3d p = T_camera_world * c.world;
  if (p.z() <= 1e-6) return std::numeric_limits<double>::infinity();
  return (Eigen::Vector2d(camera.fx * p.x() / p.z() + camera.cx,
                          camera.fy * p.y() / p.z() + camera.cy) -
          c.pixel)
      .norm();
}

std::vector<int> Inliers(const std::vector<PnpCorrespondence>& correspondences,
                         const Eigen::Isometry3d& T_camera_world,
                         const geometry::StereoCamera& camera, double threshold) {
  std::vector<int> inliers;
  for (int i = 0; i < static_cast<int>(correspondences.size()); ++i) {
    if (PixelReprojectionError(correspondences[i], T_camera_world, camera) <= threshold)
      inliers.push_back(i);
  }
  return inliers;
}

// T_camera_world from camera points and world points (rigid Umeyama fit).
Eigen::Isometry3d FitRigid(const std::vector<PnpCorrespondence>& correspondences,
                           const std::vector<int>& indices) {
  Eigen::Matrix3Xd world(3, indices.size()), cam(3, indices.size());
  for (std::size_t k = 0; k < indices.size(); ++k) {
    world.col(static_cast<Eigen::Index>(k)) = correspondences[indices[k]].world;
    cam.col(static_cast<Eigen::Index>(k)) = correspondences[indices[k]].camera_point;
  }
  return Eigen::Isometry3d(Eigen::umeyama(world, cam, false));
}

// Re-fits `best` to the correspondences `consensus` by reprojection error (Levenberg-Marquardt
// from best's pose), recounts the inliers, and again while the re-fitted pose gathers more; keeps
// best where a re-fit gathers fewer.
void RefitByReprojection(const std::vector<PnpCorrespondence>& correspondences,
                         const geometry::StereoCamera& camera, const PnpRansacOptions& options,
                         std::vector<int> consensus, PnpResult* best) {
  for (int refit = 0; refit < 3 && consensus.size() >= 6; ++refit) {
    std::vector<cv::Point3d> object;
    std::vector<cv::Point2d> image;
    for (const int i : consensus) {
      const PnpCorrespondence& c = correspondences[i];
      object.emplace_back(c.world.x(), c.world.y(), c.world.z());
      image.emplace_back(c.pixel.x(), c.pixel.y());
    }
    cv::Mat rotation_vector, translation;
    ToOpenCv(best->T_camera_world, &rotation_vector, &translation);
    if (!cv::solvePnP(object, image, camera.CameraMatrix(), cv::noArray(), rotation_vector,
                      translation, /*useExtrinsicGuess=*/true, cv::SOLVEPNP_ITERATIVE)) {
      return;
    }
    const Eigen::Isometry3d refined = FromOpenCv(rotation_vector, translation);
    std::vector<int> inliers =
        Inliers(correspondences, refined, camera, options.reprojection_threshold);
    if (inliers.size() < best->inliers.size()) return;
    const bool grew = inliers.size() > best->inliers.size();
    best->T_camera_world = refined;
    best->inliers = inliers;
    consensus = std::move(inliers);
    if (!grew) return;
  }
}

PnpResult UmeyamaRansac(const std::vector<PnpCorrespondence>& correspondences,
                        const geometry::StereoCamera& camera, const PnpRansacOptions& options) {
  // Hypotheses from close points only (within 40 baselines, where stereo depth is reliable),
  // unless there are too few of them.
  std::vector<int> with_depth, close;
  for (int i = 0; i < static_cast<int>(correspondences.size()); ++i) {
    if (!correspondences[i].has_depth) continue;
    with_depth.push_back(i);
    if (correspondences[i].camera_point.z() < 40.0 * camera.baseline) close.push_back(i);
  }
  if (close.size() >= 10) with_depth = close;
  PnpResult best;
  if (with_depth.size() < 3) return best;
  std::mt19937_64 random(options.seed);
  std::uniform_int_distribution<std::size_t> pick(0, with_depth.size() - 1);
  int iterations = options.max_iterations;
  for (int iteration = 0; iteration < iterations; ++iteration) {
    std::vector<int> sample;
    while (sample.size() < 3) {
      const int candidate = with_depth[pick(random)];
      if (std::find(sample.begin(), sample.end(), candidate) == sample.end())
        sample.push_back(candidate);
    }
    const Eigen::Isometry3d hypothesis = FitRigid(correspondences, sample);
    std::vector<int> inliers =
        Inliers(correspondences, hypothesis, camera, options.reprojection_threshold);
    if (inliers.size() > best.inliers.size()) {
      best.success = true;
      best.T_camera_world = hypothesis;
      best.inliers = std::move(inliers);
      // Standard adaptive iteration count for a 3-point sample.
      const double ratio = static_cast<double>(best.inliers.size()) / correspondences.size();
      const double needed = std::log(1.0 - options.confidence) / std::log(1.0 - std::pow(ratio, 3));
      iterations = std::min(options.max_iterations, static_cast<int>(std::ceil(needed)));
    }
  }
  // Stereo depth errors grow with the square of the depth and dominate a 3-D fit; re-fitted by
  // reprojection error instead, as OpenCV does for its own kernels.
  if (best.success) RefitByReprojection(correspondences, camera, options, best.inliers, &best);
  return best;
}

}  // namespace

std::optional<PnpKernel> ParsePnpKernel(const std::string& name) {
  for (const auto& k : kPnpKernelNames) {
    if (name == k.name) return k.value;
  }
  return std::nullopt;
}

std::string PnpKernelNames() {
  std::string names;
  for (const auto& k : kPnpKernelNames) names += (names.empty() ? "" : ", ") + std::string(k.name);
  return names;
}

PnpResult SolvePnpRansac(const std::vector<PnpCorrespondence>& correspondences,
                         const geometry::StereoCamera& camera, const PnpRansacOptions& options,
                         const Eigen::Isometry3d& guess) {
  if (options.kernel == PnpKernel::kUmeyama) return UmeyamaRansac(correspondences, camera, options);
  PnpResult result;
  if (correspondences.size() < 6) return result;
  std::vector<cv::Point3d> object;
  std::vector<cv::Point2d> image;
  for (const PnpCorrespondence& c : correspondences) {
    object.emplace_back(c.world.x(), c.world.y(), c.world.z());
    image.emplace_back(c.pixel.x(), c.pixel.y());
  }
  cv::Mat rotation_vector, translation;
  const Eigen::AngleAxisd guess_rotation(guess.linear());
  const Eigen::Vector3d guess_vector = guess_rotation.angle() * guess_rotation.axis();
  rotation_vector =
      (cv::Mat_<double>(3, 1) << guess_vector.x(), guess_vector.y(), guess_vector.z());
  translation = (cv::Mat_<double>(3, 1) << guess.translation().x(), guess.translation().y(),
                 guess.translation().z());
  std::vector<int> inliers;
  const bool use_guess = options.kernel == PnpKernel::kIterative;
  if (!cv::solvePnPRansac(object, image, camera.CameraMatrix(), cv::noArray(), rotation_vector,
                          translation, use_guess, options.max_iterations,
                          static_cast<float>(options.reprojection_threshold), options.confidence,
                          inliers, OpenCvFlag(options.kernel))) {
    return result;
  }
  result.T_camera_world = FromOpenCv(rotation_vector, translation);
  // Inliers recounted with our own test, so that every kernel is judged the same way.
  result.inliers =
      Inliers(correspondences, result.T_camera_world, camera, options.reprojection_threshold);
  // OpenCV re-fits its consensus set with EPnP after a 3-point kernel (AP3P, P3P). On a nearly
  // planar, repetitive scene that fit can land pixels away: on MH01's pallets OpenCV's consensus
  // of 218 left 13 within the threshold, and the frame was lost. So the consensus is re-fitted by
  // reprojection error from there, and the pose that keeps more inliers wins. ITERATIVE's own
  // re-fit is already that one.
  if (options.kernel != PnpKernel::kIterative && !inliers.empty()) {
    RefitByReprojection(correspondences, camera, options, std::move(inliers), &result);
  }
  result.success = result.inliers.size() >= 6;
  return result;
}

}  // namespace stereo_fabmap_slam::geometry
