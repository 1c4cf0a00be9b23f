#pragma once

#include <limits>
#include <optional>
#include <string>
#include <vector>

#include <Eigen/Geometry>
#include <opencv2/core.hpp>

#include "stereo_fabmap_slam/geometry/stereo_camera.h"

namespace stereo_fabmap_slam::evaluation {

// When two posed frames show the same place (FromPoses).
struct PlaceRelevance {
  double tau = 0.5;  // the fraction of a frame's points the other camera must see
  // Both frames must see tau of each other's points, not one of the other's. Looking down a
  // corridor, the view from 20 m back sees the doors ahead (far and small) but not the other
  // way round: with `mutual` it is another place, as it is for the loop detector.
  bool mutual = false;
  double max_distance = std::numeric_limits<double>::infinity();  // [m] between the cameras
};

// Which frames of a sequence show the same place: a symmetric N x N relation, from the
// ground-truth poses or from a matrix shipped with an image folder.
class PlaceGroundTruth {
 public:
  // `same`: N x N, CV_8U, non-zero = same place. Read symmetrically: i and j are the same place
  // if either entry says so (benchmarks often fill only one triangle). Throws
  // std::invalid_argument if it is not square.
  explicit PlaceGroundTruth(const cv::Mat& same);

  // A benchmark's matrix: a CSV or whitespace text file of N rows of N numbers, or a grey image
  // of N x N pixels (.png, .bmp, .tif, ...); non-zero = same place. Throws io::InputError naming
  // the file (and line) if it is unreadable, not square, or holds a field that is not a number.
  static PlaceGroundTruth Load(const std::string& path);

  // From poses: frames i and j show the same place when at least `tau` of one frame's stereo
  // points (its camera frame), carried by the ground-truth relative pose, land in front of the
  // other camera and inside its image (VisibleFraction, the relevance test of the
  // relocalization measure), in either direction. A frame without a pose (nullopt) or without
  // points is the same place as nothing but itself. Throws std::invalid_argument if the two
  // lists differ in length or tau is outside (0, 1].
  static PlaceGroundTruth FromPoses(
      const std::vector<std::vector<Eigen::Vector3d>>& points,
      const std::vector<std::optional<Eigen::Isometry3d>>& T_world_camera,
      const geometry::StereoCamera& camera, double tau);
  // The same with the relevance test's other conditions (mutual visibility, distance).
  static PlaceGroundTruth FromPoses(
      const std::vector<std::vector<Eigen::Vector3d>>& points,
      const std::vector<std::optional<Eigen::Isometry3d>>& T_world_camera,
      const geometry::StereoCamera& camera, const PlaceRelevance& relevance);

  // The relation among the frames `indices` (e.g. every n-th image of the folder), in that order.
  // Throws std::out_of_range for an index outside the matrix.
  PlaceGroundTruth Subset(const std::vector<int>& indices) const;

  int size() const { return same_.rows; }
  bool Same(int i, int j) const { return same_.at<unsigned char>(i, j) != 0; }
  // Pairs i < j that show the same place.
  long SamePairs() const;

 private:
  cv::Mat same_;  // symmetric, CV_8U 0/1
};

}  // namespace stereo_fabmap_slam::evaluation
