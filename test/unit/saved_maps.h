#pragma once

// Two saved maps compared field by field (map_file_test: through a file and into another map;
// lockstep_test: the graph's map against run_dataset's).

#include <cstddef>
#include <cstdint>

#include <gtest/gtest.h>
#include <opencv2/core.hpp>

#include "stereo_fabmap_slam/map/map_file.h"

namespace stereo_fabmap_slam::test {

// `map_tolerance`: of the keyframes' map poses; `tolerance`: of every other number (odometry
// poses, points, edges); 0 means bit for bit. A map loaded into a running one passes its map
// poses through the pose graph's quaternions (1e-12 relative); two drivers' maps differ in the
// last digits of what they exchanged as messages (1e-9).
inline void ExpectSameMaps(const map::SavedMap& a, const map::SavedMap& b,
                           double map_tolerance = 0.0, double tolerance = 0.0) {
  const auto expect_same = [](const auto& x, const auto& y, double within, std::int64_t id) {
    if (within == 0.0) {
      EXPECT_EQ(x, y) << "keyframe " << id;
    } else {
      EXPECT_TRUE(x.isApprox(y, within)) << "keyframe " << id;
    }
  };
  EXPECT_EQ(a.vocabulary_fingerprint, b.vocabulary_fingerprint);
  EXPECT_EQ(a.camera.size, b.camera.size);
  // A rig that passed through a message (a keyframe's camera fields) may differ in the last bits.
  if (tolerance == 0.0) {
    EXPECT_EQ(a.camera.fx, b.camera.fx);
    EXPECT_EQ(a.camera.baseline, b.camera.baseline);
  } else {
    EXPECT_DOUBLE_EQ(a.camera.fx, b.camera.fx);
    EXPECT_DOUBLE_EQ(a.camera.baseline, b.camera.baseline);
  }
  ASSERT_EQ(a.keyframes.size(), b.keyframes.size());
  for (std::size_t i = 0; i < a.keyframes.size(); ++i) {
    const map::Keyframe& x = a.keyframes[i].keyframe;
    const map::Keyframe& y = b.keyframes[i].keyframe;
    ASSERT_EQ(x.id, y.id);
    // Stamps that passed through ROS messages (integer nanoseconds) may differ in the last bit
    // of a double near 1.4e9 s (2e-7 s).
    EXPECT_NEAR(x.timestamp, y.timestamp, tolerance == 0.0 ? 0.0 : 1e-6) << x.id;
    EXPECT_EQ(x.starts_new_segment, y.starts_new_segment) << x.id;
    expect_same(x.T_world_camera.matrix(), y.T_world_camera.matrix(), tolerance, x.id);
    expect_same(a.keyframes[i].T_map_camera.matrix(), b.keyframes[i].T_map_camera.matrix(),
                map_tolerance, x.id);
    EXPECT_EQ(a.keyframes[i].words, b.keyframes[i].words) << x.id;
    ASSERT_EQ(x.features.size(), y.features.size()) << x.id;
    EXPECT_EQ(cv::norm(x.features.descriptors, y.features.descriptors, cv::NORM_L1), 0.0) << x.id;
    EXPECT_EQ(x.features.u_right, y.features.u_right) << x.id;
    EXPECT_EQ(x.map_point_ids, y.map_point_ids) << x.id;
    for (std::size_t k = 0; k < x.features.size(); ++k) {
      expect_same(x.features.points[k], y.features.points[k], tolerance, x.id);
      EXPECT_EQ(x.features.keypoints[k].pt, y.features.keypoints[k].pt) << x.id;
      EXPECT_EQ(x.features.keypoints[k].size, y.features.keypoints[k].size) << x.id;
      EXPECT_EQ(x.features.keypoints[k].octave, y.features.keypoints[k].octave) << x.id;
    }
  }
  ASSERT_EQ(a.edges.size(), b.edges.size());
  for (std::size_t i = 0; i < a.edges.size(); ++i) {
    const map::LoopEdge& x = a.edges[i].edge;
    const map::LoopEdge& y = b.edges[i].edge;
    EXPECT_EQ(x.match_id, y.match_id);
    EXPECT_EQ(x.query_id, y.query_id);
    expect_same(x.T_match_query.matrix(), y.T_match_query.matrix(), tolerance, x.query_id);
    expect_same(x.information, y.information, tolerance, x.query_id);
    EXPECT_EQ(a.edges[i].relocalization, b.edges[i].relocalization);
  }
}

}  // namespace stereo_fabmap_slam::test
