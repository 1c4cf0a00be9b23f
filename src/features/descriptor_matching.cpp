#include "stereo_fabmap_slam/features/descriptor_matching.h"

#include <opencv2/features2d.hpp>

namespace stereo_fabmap_slam::features {

std::vector<cv::DMatch> RatioTestMatches(const cv::Mat& query, const cv::Mat& train, int norm,
                                         double max_distance, double ratio) {
  std::vector<cv::DMatch> matches;
  if (query.empty() || train.empty()) return matches;
  cv::BFMatcher matcher(norm);
  std::vector<std::vector<cv::DMatch>> knn;
  matcher.knnMatch(query, train, knn, 2);
  for (const std::vector<cv::DMatch>& pair : knn) {
    if (pair.empty() || pair[0].distance > max_distance) continue;
    if (pair.size() > 1 && pair[0].distance >= ratio * pair[1].distance) continue;
    matches.push_back(pair[0]);
  }
  return matches;
}

}  // namespace stereo_fabmap_slam::features
