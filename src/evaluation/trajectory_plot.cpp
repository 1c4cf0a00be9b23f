#include "stereo_fabmap_slam/evaluation/trajectory_plot.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>

#include <opencv2/imgproc.hpp>

namespace stereo_fabmap_slam::evaluation {
namespace {

// Grid spacing of 1, 2 or 5 times a power of ten giving about `lines` lines over `extent`.
double NiceStep(double extent, double lines) {
  const double raw = extent / lines;
  const double power = std::pow(10.0, std::floor(std::log10(raw)));
  for (const double factor : {1.0, 2.0, 5.0}) {
    if (factor * power >= raw) return factor * power;
  }
  return 10.0 * power;
}

std::string FormatMetres(double value, double step) {
  char text[32];
  const int decimals = step >= 1.0 ? 0 : static_cast<int>(std::ceil(-std::log10(step)));
  std::snprintf(text, sizeof(text), "%.*f", decimals, value);
  return text;
}

}  // namespace

void TrajectoryPlot::AddPath(const std::vector<Eigen::Vector3d>& positions, const cv::Scalar& color,
                             const std::string& label, int thickness) {
  layers_.push_back({Layer::Kind::kPath, positions, color, label, thickness});
}

void TrajectoryPlot::AddPoints(const std::vector<Eigen::Vector3d>& positions,
                               const cv::Scalar& color, const std::string& label, int radius) {
  layers_.push_back({Layer::Kind::kPoints, positions, color, label, radius});
}

void TrajectoryPlot::AddSegments(
    const std::vector<std::pair<Eigen::Vector3d, Eigen::Vector3d>>& segments,
    const cv::Scalar& color, const std::string& label, int thickness) {
  Layer layer{Layer::Kind::kSegments, {}, color, label, thickness};
  for (const auto& [from, to] : segments) {
    layer.positions.push_back(from);
    layer.positions.push_back(to);
  }
  layers_.push_back(std::move(layer));
}

cv::Mat TrajectoryPlot::Render(const cv::Size& size, const std::string& title,
                               PlotView view) const {
  cv::Mat image(size, CV_8UC3, cv::Scalar(255, 255, 255));
  // The vertical axis of the picture: y seen from above, z from the side.
  const int vertical = view == PlotView::kTop ? 1 : 2;
  double min_x = std::numeric_limits<double>::infinity(), max_x = -min_x;
  double min_y = min_x, max_y = -min_x;
  for (const Layer& layer : layers_) {
    for (const Eigen::Vector3d& p : layer.positions) {
      min_x = std::min(min_x, p.x());
      max_x = std::max(max_x, p.x());
      min_y = std::min(min_y, p[vertical]);
      max_y = std::max(max_y, p[vertical]);
    }
  }
  if (!std::isfinite(min_x)) {
    min_x = min_y = -1.0;
    max_x = max_y = 1.0;
  }
  // Equal scales on both axes, a margin for labels, and at least 10 cm of extent.
  const int margin_left = 70, margin_right = 20, margin_top = 40, margin_bottom = 50;
  const double plot_width = size.width - margin_left - margin_right;
  const double plot_height = size.height - margin_top - margin_bottom;
  const double extent_x = std::max(max_x - min_x, 0.1), extent_y = std::max(max_y - min_y, 0.1);
  const double scale = 0.95 * std::min(plot_width / extent_x, plot_height / extent_y);
  const double center_x = 0.5 * (min_x + max_x), center_y = 0.5 * (min_y + max_y);
  const auto to_pixel = [&](double x, double y) {
    return cv::Point(
        static_cast<int>(std::lround(margin_left + plot_width / 2 + (x - center_x) * scale)),
        static_cast<int>(std::lround(margin_top + plot_height / 2 - (y - center_y) * scale)));
  };

  // Grid with labels in metres.
  const double view_x = plot_width / scale, view_y = plot_height / scale;
  const double step = NiceStep(std::max(view_x, view_y), 8.0);
  const cv::Scalar grid_color(225, 225, 225), text_color(60, 60, 60);
  const int font = cv::FONT_HERSHEY_SIMPLEX;
  for (double x = std::ceil((center_x - view_x / 2) / step) * step; x <= center_x + view_x / 2;
       x += step) {
    const cv::Point top = to_pixel(x, center_y + view_y / 2),
                    bottom = to_pixel(x, center_y - view_y / 2);
    cv::line(image, top, bottom, grid_color, 1);
    cv::putText(image, FormatMetres(x, step), bottom + cv::Point(-12, 18), font, 0.4, text_color);
  }
  for (double y = std::ceil((center_y - view_y / 2) / step) * step; y <= center_y + view_y / 2;
       y += step) {
    const cv::Point left = to_pixel(center_x - view_x / 2, y),
                    right = to_pixel(center_x + view_x / 2, y);
    cv::line(image, left, right, grid_color, 1);
    cv::putText(image, FormatMetres(y, step), left + cv::Point(-55, 4), font, 0.4, text_color);
  }
  cv::putText(image, "x [m]", cv::Point(size.width / 2, size.height - 12), font, 0.5, text_color);
  cv::putText(image, view == PlotView::kTop ? "y [m]" : "z [m]", cv::Point(8, margin_top - 12),
              font, 0.5, text_color);
  if (!title.empty()) {
    cv::putText(image, title, cv::Point(margin_left, 24), font, 0.6, cv::Scalar(0, 0, 0), 1,
                cv::LINE_AA);
  }

  for (const Layer& layer : layers_) {
    std::vector<cv::Point> pixels;
    for (const Eigen::Vector3d& p : layer.positions) {
      pixels.push_back(to_pixel(p.x(), p[vertical]));
    }
    switch (layer.kind) {
      case Layer::Kind::kPath:
        cv::polylines(image, pixels, false, layer.color, layer.width, cv::LINE_AA);
        if (!pixels.empty()) cv::circle(image, pixels.front(), 5, layer.color, 1, cv::LINE_AA);
        break;
      case Layer::Kind::kPoints:
        for (const cv::Point& p : pixels)
          cv::circle(image, p, layer.width, layer.color, cv::FILLED);
        break;
      case Layer::Kind::kSegments:
        for (std::size_t i = 0; i + 1 < pixels.size(); i += 2) {
          cv::line(image, pixels[i], pixels[i + 1], layer.color, layer.width, cv::LINE_AA);
        }
        break;
    }
  }

  // Legend in the top right corner; the circle on a path marks its start.
  int row = margin_top + 8;
  for (const Layer& layer : layers_) {
    if (layer.label.empty()) continue;
    const cv::Point anchor(size.width - margin_right - 190, row);
    cv::line(image, anchor, anchor + cv::Point(24, 0), layer.color, 3, cv::LINE_AA);
    cv::putText(image, layer.label, anchor + cv::Point(32, 5), font, 0.45, text_color, 1,
                cv::LINE_AA);
    row += 20;
  }
  return image;
}

}  // namespace stereo_fabmap_slam::evaluation
