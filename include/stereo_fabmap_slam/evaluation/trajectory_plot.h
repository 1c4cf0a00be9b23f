#pragma once

#include <string>
#include <utility>
#include <vector>

#include <Eigen/Core>
#include <opencv2/core.hpp>

namespace stereo_fabmap_slam::evaluation {

// Which two axes a plot shows: from above (x right, y up) or from the side (x right, z up).
enum class PlotView { kTop, kSide };

// Paths, points and segments in metres, with a metric grid, axis labels and a legend, rendered
// to an image from above or from the side. Later layers draw over earlier ones.
class TrajectoryPlot {
 public:
  void AddPath(const std::vector<Eigen::Vector3d>& positions, const cv::Scalar& color,
               const std::string& label, int thickness = 2);
  void AddPoints(const std::vector<Eigen::Vector3d>& positions, const cv::Scalar& color,
                 const std::string& label, int radius = 3);
  void AddSegments(const std::vector<std::pair<Eigen::Vector3d, Eigen::Vector3d>>& segments,
                   const cv::Scalar& color, const std::string& label, int thickness = 1);

  // A BGR image of the given size; the view fits everything added, with equal axis scales.
  cv::Mat Render(const cv::Size& size, const std::string& title = "",
                 PlotView view = PlotView::kTop) const;

 private:
  struct Layer {
    enum class Kind { kPath, kPoints, kSegments } kind;
    std::vector<Eigen::Vector3d> positions;  // segments: pairs of consecutive entries
    cv::Scalar color;
    std::string label;
    int width;
  };
  std::vector<Layer> layers_;
};

}  // namespace stereo_fabmap_slam::evaluation
