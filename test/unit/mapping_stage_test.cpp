// The mapping stage's own rules, which the offline runner and the Backend nodelet share: edges
// that arrive before their keyframes wait for them, keyframes from before a loaded map are
// dropped and the next one starts a segment, localization mode leaves the graph as it is, the
// keyframes' rig is checked, and what the other stages are told of the map (MapState) is the
// pose graph's.
#include "stereo_fabmap_slam/pipeline/mapping_stage.h"

#include <algorithm>
#include <functional>
#include <vector>

#include <gtest/gtest.h>

#include "stereo_fabmap_slam/geometry/relative_pose_error.h"
#include "stereo_fabmap_slam/io/input_error.h"
#include "stereo_world.h"

namespace stereo_fabmap_slam::test {
namespace {

class MappingStageTest : public ::testing::Test {
 protected:
  MappingStageTest()
      : stage_(backend::BundleAdjustmentOptions(), backend::PoseGraphOptions(),
               [] { return 0.0; }) {
    world_.Add(RandomPoints(300, 3), 5);
  }

  // Keyframe `id` of a camera moving 10 cm a keyframe along x, seeing the same points (new
  // point ids each time: the window has nothing to adjust but the poses it was given).
  map::Keyframe Keyframe(std::int64_t id, bool starts_new_segment = false) const {
    map::Keyframe keyframe;
    keyframe.id = id;
    keyframe.timestamp = 0.5 * id;
    keyframe.T_world_camera = Eigen::Isometry3d(Eigen::Translation3d(0.1 * id, 0, 0));
    keyframe.starts_new_segment = starts_new_segment;
    keyframe.features = Observe(world_, keyframe.T_world_camera);
    keyframe.map_point_ids.resize(keyframe.features.size());
    for (std::size_t k = 0; k < keyframe.map_point_ids.size(); ++k) {
      keyframe.map_point_ids[k] = 1000 * id + static_cast<std::int64_t>(k);
    }
    return keyframe;
  }

  // Keyframe(id) with each observation's id the world point it is (exact observations: the
  // nearest one), so that consecutive keyframes share their points as a tracker's would.
  map::Keyframe SharedPointsKeyframe(std::int64_t id) const {
    map::Keyframe keyframe = Keyframe(id);
    for (std::size_t k = 0; k < keyframe.map_point_ids.size(); ++k) {
      const Eigen::Vector3d point = keyframe.T_world_camera * keyframe.features.points[k];
      std::size_t nearest = 0;
      for (std::size_t i = 1; i < world_.points.size(); ++i) {
        if ((world_.points[i] - point).norm() < (world_.points[nearest] - point).norm())
          nearest = i;
      }
      keyframe.map_point_ids[k] = static_cast<std::int64_t>(nearest);
    }
    return keyframe;
  }

  static map::LoopEdge Edge(std::int64_t match, std::int64_t query, double dx) {
    map::LoopEdge edge;
    edge.match_id = match;
    edge.query_id = query;
    edge.T_match_query = Eigen::Isometry3d(Eigen::Translation3d(dx, 0, 0));
    edge.information = geometry::DiagonalPoseInformation(0.02, 0.2);
    return edge;
  }

  // A second pass: keyframes 6-8 stand where 0-2 stood, but the odometry puts them 5 cm further
  // along x, and they name the same 300 points anew (1000 + i). The loop 6 -> 0 (exact, 2 cm
  // sigma) carries the pairs of points its verification matched (`pair_of`: the first pass's point
  // a second pass's point i was matched to, or -1 for none). Returns how far the second pass's
  // keyframes end from their true places after the refinement.
  struct SecondPassErrors {
    double revisit;  // keyframe 6 [m]; its true place is the origin
    double largest;  // of keyframes 6-8
  };
  SecondPassErrors SecondPassErrorsAfterRefinement(
      const backend::GlobalRefinementOptions& options,
      const std::function<std::int64_t(std::int64_t)>& pair_of) const {
    const auto second_pass = [this](std::int64_t id) {
      map::Keyframe keyframe = SharedPointsKeyframe(id - 6);
      keyframe.id = id;
      keyframe.timestamp = 0.5 * id;
      keyframe.T_world_camera.translation().x() += 0.05;
      for (std::int64_t& point : keyframe.map_point_ids) point += 1000;
      return keyframe;
    };
    pipeline::MappingStage stage(backend::BundleAdjustmentOptions(), backend::PoseGraphOptions(),
                                 [] { return 0.0; });
    stage.SetGlobalRefinement(options);
    for (std::int64_t id = 0; id < 6; ++id)
      stage.AddKeyframe(SharedPointsKeyframe(id), kTestCamera);
    for (std::int64_t id = 6; id < 9; ++id) stage.AddKeyframe(second_pass(id), kTestCamera);
    map::LoopEdge loop = Edge(0, 6, 0.0);
    for (const std::int64_t point : second_pass(6).map_point_ids) {
      const std::int64_t match = pair_of(point - 1000);
      if (match >= 0) loop.shared_points.emplace_back(point, match);
    }
    stage.AddEdge(loop, backend::PoseGraphEdgeType::kLoop);
    EXPECT_EQ(stage.global_refinements(), 1u);
    SecondPassErrors errors{stage.MapPose(6).translation().norm(), 0.0};
    for (std::int64_t id = 6; id < 9; ++id) {
      const Eigen::Vector3d truth = SharedPointsKeyframe(id - 6).T_world_camera.translation();
      errors.largest = std::max(errors.largest, (stage.MapPose(id).translation() - truth).norm());
    }
    return errors;
  }

  StereoWorld world_;
  pipeline::MappingStage stage_;
};

TEST_F(MappingStageTest, KeyframesJoinTheGraphAndTheMapIsTheFirstOnesPiece) {
  for (std::int64_t id = 0; id < 3; ++id) {
    const pipeline::MappedKeyframe mapped = stage_.AddKeyframe(Keyframe(id), kTestCamera);
    EXPECT_TRUE(mapped.in_map_graph);
    EXPECT_EQ(mapped.keyframe_id, id);
  }
  const pipeline::MappedKeyframe lost = stage_.AddKeyframe(Keyframe(3, true), kTestCamera);
  EXPECT_TRUE(lost.starts_new_segment);
  EXPECT_TRUE(stage_.InMap(2));
  EXPECT_FALSE(stage_.InMap(3)) << "a new segment is a piece of its own";
  EXPECT_FALSE(stage_.InMap(99)) << "a keyframe the map does not hold";
  // The snapshot the nodelets pass around says the same.
  const pipeline::MapSnapshot snapshot = stage_.Snapshot();
  EXPECT_TRUE(snapshot.InMap(2));
  EXPECT_FALSE(snapshot.InMap(3));
  EXPECT_TRUE(snapshot.MapPose(2).isApprox(stage_.MapPose(2)));
  EXPECT_THROW(stage_.MapPose(99), std::out_of_range);
}

// With the pose graph weighing its odometry edges by the bundle adjustment's step covariances,
// the stage has the adjuster estimate them and the graph's edges carry them: keyframes that
// share their points (the same ids each time) give each step a covariance of millimetres, whose
// information is far above the fixed sigmas' (2 cm: 2,500 / m^2). Without the option the edges
// keep the fixed sigmas and the updates carry no covariances.
TEST_F(MappingStageTest, StepCovariancesReachThePoseGraphsOdometryEdgesWhenAsked) {
  backend::PoseGraphOptions weighed;
  weighed.odometry_covariance_scale = 1.0;
  pipeline::MappingStage stage(backend::BundleAdjustmentOptions(), weighed, [] { return 0.0; });
  std::size_t covariances = 0;
  for (std::int64_t id = 0; id < 4; ++id) {
    covariances +=
        stage.AddKeyframe(SharedPointsKeyframe(id), kTestCamera).update.step_covariances.size();
    EXPECT_TRUE(
        stage_.AddKeyframe(SharedPointsKeyframe(id), kTestCamera).update.step_covariances.empty());
  }
  EXPECT_GE(covariances, 3u);
  const Eigen::Matrix<double, 6, 6> fixed = stage_.pose_graph().Edges().front().information;
  for (const backend::PoseGraphEdge& edge : stage.pose_graph().Edges()) {
    EXPECT_GT(edge.information(0, 0), 100 * fixed(0, 0)) << edge.from << " -> " << edge.to;
  }
  for (const backend::PoseGraphEdge& edge : stage_.pose_graph().Edges()) {
    EXPECT_TRUE(edge.information.isApprox(fixed)) << edge.from << " -> " << edge.to;
  }
}

// Six keyframes 10 cm apart see the same 300 points exactly; a loop 5 -> 0 claims 3 cm more
// than the truth (0.5 m). The pose graph, whose odometry edges carry 2 cm each, gives the loop
// most of its way (keyframe 5 moves 2.5 cm); with the refinement after loop closing the points
// hold every step, the loop's 3 cm stays in the loop edge (1.5 of its sigmas), and the graph keeps
// the refined poses: keyframe 5 within 2 mm of its odometry pose, which is the truth here.
// Keyframe 0, the map's anchor, stays where it was either way.
TEST_F(MappingStageTest, AfterALoopClosesTheWholeMapIsRefinedWhenAsked) {
  pipeline::MappingStage refining(backend::BundleAdjustmentOptions(), backend::PoseGraphOptions(),
                                  [] { return 0.0; });
  backend::GlobalRefinementOptions options;
  options.after_loop_closing = true;
  refining.SetGlobalRefinement(options);
  for (std::int64_t id = 0; id < 6; ++id) {
    refining.AddKeyframe(SharedPointsKeyframe(id), kTestCamera);
    stage_.AddKeyframe(SharedPointsKeyframe(id), kTestCamera);
  }
  EXPECT_EQ(refining.RefineGlobally(options).keyframes, 0u) << "nothing to refine without loops";
  EXPECT_EQ(refining.global_refinements(), 0u);
  const Eigen::Isometry3d odometry_5 = SharedPointsKeyframe(5).T_world_camera;
  const map::LoopEdge loop = Edge(0, 5, 0.53);
  refining.AddEdge(loop, backend::PoseGraphEdgeType::kLoop);
  stage_.AddEdge(loop, backend::PoseGraphEdgeType::kLoop);
  EXPECT_EQ(refining.global_refinements(), 1u);
  EXPECT_GT((stage_.MapPose(5).translation() - odometry_5.translation()).norm(), 0.02);
  EXPECT_LT((refining.MapPose(5).translation() - odometry_5.translation()).norm(), 0.002);
  EXPECT_TRUE(refining.MapPose(0).isApprox(stage_.MapPose(0), 1e-12));
}

// Without fusing the shared points the two passes are joined by the loop and the odometry step
// 5 -> 6 (no point is shared across it), which disagree by 5 cm: keyframe 6 ends between them
// (6.4 mm from the truth: the loop's 2 cm against the step's 2 cm and 0.1 degrees, under the
// loop's Cauchy loss). With the points fused, the first pass's exact observations put it back to
// the truth (to well under a millimetre).
TEST_F(MappingStageTest, ARefinementFusesThePointsALoopSawOnBothPasses) {
  backend::GlobalRefinementOptions fused, separate;
  fused.after_loop_closing = separate.after_loop_closing = true;
  separate.fuse_loop_points = false;
  const auto same_point = [](std::int64_t point) { return point; };
  const double fused_error = SecondPassErrorsAfterRefinement(fused, same_point).revisit;
  const double separate_error = SecondPassErrorsAfterRefinement(separate, same_point).revisit;
  RecordProperty("fused_error_mm", std::to_string(fused_error * 1000));
  RecordProperty("separate_error_mm", std::to_string(separate_error * 1000));
  EXPECT_LT(fused_error, 0.0005);
  EXPECT_GT(separate_error, 0.003);
}

// Look-alikes: each second-pass point paired with a first-pass point more than half a metre from
// it (the next door of a corridor). With the distance check none is fused, and the second pass
// ends where it ends without fusing (to 0.1 mm: the same problem). With the check off they are
// fused: the outlier test then takes the second pass's observations of its fused points out,
// which are all it had, and keyframes 7 and 8, held by nothing, end metres away (15.4 m here;
// the bound, 1 m, is twenty times the 5 cm by which the loop and the odometry disagree).
TEST_F(MappingStageTest, LoopPointsFarApartInTheMapAreNotFused) {
  const auto look_alike = [this](std::int64_t point) -> std::int64_t {
    for (std::size_t other = 0; other < world_.points.size(); ++other) {
      const std::size_t candidate =
          (static_cast<std::size_t>(point) + 1 + other) % world_.points.size();
      if ((world_.points[candidate] - world_.points[static_cast<std::size_t>(point)]).norm() > 0.5)
        return static_cast<std::int64_t>(candidate);
    }
    return -1;
  };
  backend::GlobalRefinementOptions checked, unchecked, separate;
  checked.after_loop_closing = unchecked.after_loop_closing = separate.after_loop_closing = true;
  unchecked.fuse_max_distance = 1e9;
  separate.fuse_loop_points = false;
  const auto same_point = [](std::int64_t point) { return point; };
  const double checked_error = SecondPassErrorsAfterRefinement(checked, look_alike).largest;
  const double unchecked_error = SecondPassErrorsAfterRefinement(unchecked, look_alike).largest;
  const double separate_error = SecondPassErrorsAfterRefinement(separate, same_point).largest;
  RecordProperty("checked_error_mm", std::to_string(checked_error * 1000));
  RecordProperty("unchecked_error_mm", std::to_string(unchecked_error * 1000));
  EXPECT_NEAR(checked_error, separate_error, 1e-4);
  EXPECT_GT(unchecked_error, 1.0);
}

// In localization mode the map stays as it is: no refinement, even with loops in the graph.
TEST_F(MappingStageTest, LocalizationModeRefinesNothing) {
  backend::GlobalRefinementOptions options;
  pipeline::MappingStage stage(backend::BundleAdjustmentOptions(), backend::PoseGraphOptions(),
                               [] { return 0.0; });
  for (std::int64_t id = 0; id < 6; ++id) stage.AddKeyframe(SharedPointsKeyframe(id), kTestCamera);
  stage.AddEdge(Edge(0, 5, 0.53), backend::PoseGraphEdgeType::kLoop);
  const Eigen::Isometry3d before = stage.MapPose(5);
  stage.SetMode(pipeline::SlamMode::kLocalization);
  EXPECT_EQ(stage.RefineGlobally(options).keyframes, 0u);
  EXPECT_EQ(stage.global_refinements(), 0u);
  EXPECT_TRUE(stage.MapPose(5).isApprox(before, 1e-12));
  stage.SetMode(pipeline::SlamMode::kMapping);
  EXPECT_GT(stage.RefineGlobally(options).keyframes, 0u);
  EXPECT_EQ(stage.global_refinements(), 1u);
}

TEST_F(MappingStageTest, AnEdgeWaitsForItsKeyframesThenJoinsTheSegments) {
  stage_.AddKeyframe(Keyframe(0), kTestCamera);
  stage_.AddKeyframe(Keyframe(1), kTestCamera);
  // The place stage is ahead of the bundle adjustment: the edge's query is not mapped yet.
  EXPECT_EQ(stage_.AddEdge(Edge(0, 2, 0.2), backend::PoseGraphEdgeType::kRelocalization), 0.0);
  EXPECT_EQ(stage_.waiting_edges(), 1u);
  EXPECT_EQ(stage_.relocalization_edges_received(), 1u);
  const std::uint64_t optimisations = stage_.optimisations();
  stage_.AddKeyframe(Keyframe(2, true), kTestCamera);
  EXPECT_EQ(stage_.waiting_edges(), 0u);
  EXPECT_GT(stage_.optimisations(), optimisations);
  EXPECT_TRUE(stage_.InMap(2)) << "the edge joined the new segment to the map";
  EXPECT_EQ(stage_.LoopEdges().size(), 1u);
}

TEST_F(MappingStageTest, AnEdgeToAKeyframeThatNeverComesIsDropped) {
  for (std::int64_t id : {0, 1, 3}) stage_.AddKeyframe(Keyframe(id), kTestCamera);
  // Keyframe 2 never joined (ids come in order: it never will).
  stage_.AddEdge(Edge(0, 2, 0.2), backend::PoseGraphEdgeType::kLoop);
  EXPECT_EQ(stage_.waiting_edges(), 0u);
  EXPECT_TRUE(stage_.LoopEdges().empty());
  // An edge the graph refuses is said so, not thrown at the driver.
  stage_.AddEdge(Edge(1, 1, 0.0), backend::PoseGraphEdgeType::kLoop);
  EXPECT_EQ(stage_.TakeRefusedEdges().size(), 1u);
}

TEST_F(MappingStageTest, LoopDetectionsCloseKeyframesAndKeyframesWithoutOneAreClosedAtOnce) {
  stage_.AddKeyframe(Keyframe(0), kTestCamera);
  EXPECT_EQ(stage_.last_closed_keyframe(), -1) << "a place: its loop detection is to come";
  stage_.ApplyLoopDetection(0, std::nullopt);
  EXPECT_EQ(stage_.last_closed_keyframe(), 0);
  stage_.SetMode(pipeline::SlamMode::kLocalization);
  const pipeline::MappedKeyframe localized = stage_.AddKeyframe(Keyframe(1), kTestCamera);
  EXPECT_FALSE(localized.in_map_graph) << "localization does not extend the map";
  EXPECT_EQ(stage_.last_closed_keyframe(), 1) << "no place, nothing to wait for";
  EXPECT_EQ(stage_.pose_graph().size(), 1u);
}

// A tracking loss that the odometry bridged (the tracker's keyframe starts a segment): the stage
// gives the pose graph the loss's gap (0.5 s between the keyframes here), which joins it once a
// loop closes the cycle through it. A segment the stage starts itself (after localization mode
// or a loaded map, below) has no gap.
TEST_F(MappingStageTest, ATrackingLossGivesThePoseGraphItsGap) {
  for (std::int64_t id = 0; id < 3; ++id) stage_.AddKeyframe(Keyframe(id), kTestCamera);
  stage_.AddKeyframe(Keyframe(3, true), kTestCamera);
  stage_.AddKeyframe(Keyframe(4), kTestCamera);
  EXPECT_FALSE(stage_.InMap(3));
  stage_.AddEdge(Edge(1, 4, 0.3), backend::PoseGraphEdgeType::kLoop);  // the truth: 0.3 m
  EXPECT_TRUE(stage_.InMap(3));
  const std::vector<backend::PoseGraphEdge> edges = stage_.pose_graph().Edges();
  const auto gaps = std::count_if(edges.begin(), edges.end(), [](const backend::PoseGraphEdge& e) {
    return e.type == backend::PoseGraphEdgeType::kOdometry && e.from == 2 && e.to == 3;
  });
  EXPECT_EQ(gaps, 1);
  EXPECT_EQ(stage_.LoopEdges().size(), 1u) << "a gap is no loop: maps do not save it";
}

TEST_F(MappingStageTest, LocalizationsMapToOdomIsTheTrackersAndMappingStartsASegmentAfter) {
  stage_.AddKeyframe(Keyframe(0), kTestCamera);
  stage_.SetMode(pipeline::SlamMode::kLocalization);
  const Eigen::Isometry3d correction(Eigen::Translation3d(1, 2, 3));
  stage_.SetLocalizationCorrection(correction);
  EXPECT_TRUE(stage_.MapToOdom().isApprox(correction));
  stage_.AddKeyframe(Keyframe(1), kTestCamera);
  stage_.SetMode(pipeline::SlamMode::kMapping);
  EXPECT_TRUE(stage_.MapToOdom().isApprox(Eigen::Isometry3d::Identity()));
  const pipeline::MappedKeyframe back = stage_.AddKeyframe(Keyframe(2), kTestCamera);
  EXPECT_TRUE(back.in_map_graph);
  EXPECT_TRUE(back.starts_new_segment) << "the keyframes in between are not in the graph";
  EXPECT_FALSE(stage_.InMap(2));
  stage_.AddKeyframe(Keyframe(3), kTestCamera);
  stage_.AddEdge(Edge(0, 3, 0.3), backend::PoseGraphEdgeType::kLoop);
  for (const backend::PoseGraphEdge& edge : stage_.pose_graph().Edges())
    EXPECT_FALSE(edge.from == 0 && edge.to == 2) << "no gap across localization mode";
}

TEST_F(MappingStageTest, ALoadedMapDropsOlderKeyframesAndTheNextStartsASegment) {
  map::SavedMap saved;
  saved.camera = kTestCamera;
  for (std::int64_t id = 0; id < 5; ++id) {
    map::SavedKeyframe keyframe;
    keyframe.keyframe.id = id;
    keyframe.keyframe.T_world_camera = Eigen::Isometry3d(Eigen::Translation3d(0.1 * id, 0, 0));
    keyframe.T_map_camera = keyframe.keyframe.T_world_camera;
    saved.keyframes.push_back(keyframe);
  }
  stage_.Load(saved);
  EXPECT_EQ(stage_.loaded_below(), 5);
  EXPECT_EQ(stage_.last_closed_keyframe(), 4);
  const pipeline::MappedKeyframe before = stage_.AddKeyframe(Keyframe(3), kTestCamera);
  EXPECT_FALSE(before.in_map_graph) << "made before the load: its id is the map's";
  EXPECT_TRUE(before.update.keyframe_poses.empty());
  const pipeline::MappedKeyframe next = stage_.AddKeyframe(Keyframe(5), kTestCamera);
  EXPECT_TRUE(next.in_map_graph);
  EXPECT_TRUE(next.starts_new_segment);
  EXPECT_TRUE(stage_.InMap(4));
  EXPECT_FALSE(stage_.InMap(5)) << "found in the loaded map only by relocalization or a loop";

  // A keyframe of another rig than the map's is refused.
  geometry::StereoCamera other = kTestCamera;
  other.baseline *= 1.5;
  EXPECT_THROW(stage_.AddKeyframe(Keyframe(6), other), std::invalid_argument);

  // A map whose graph cannot be rebuilt is refused and changes nothing.
  map::SavedMap broken = saved;
  broken.edges.push_back({Edge(2, 2, 0.0), false});
  EXPECT_THROW(pipeline::MappingStage::CheckGraph(broken), io::InputError);
  EXPECT_THROW(stage_.Load(broken), io::InputError);
  EXPECT_EQ(stage_.pose_graph().size(), 6u);
}

// The Backend's way of taking what waited while it worked: every keyframe joins, one bundle
// adjustment after the newest covers them all, the other inputs are taken in their order, and
// an input that cannot be taken is said and skipped.
TEST_F(MappingStageTest, ABatchAddsEveryKeyframeAndAdjustsOnlyAfterTheNewest) {
  stage_.Take({pipeline::KeyframeInput{Keyframe(0), kTestCamera}});
  geometry::StereoCamera other = kTestCamera;
  other.baseline *= 1.5;
  const pipeline::MappingBatchResult result = stage_.Take({
      pipeline::KeyframeInput{Keyframe(1), kTestCamera},
      pipeline::KeyframeInput{Keyframe(2), kTestCamera},
      pipeline::LoopDetectionInput{1, std::nullopt},
      pipeline::KeyframeInput{Keyframe(3), other},  // refused: the map's rig is another
      pipeline::KeyframeInput{Keyframe(4), kTestCamera},
  });
  ASSERT_EQ(result.keyframes.size(), 3u) << "one answer per keyframe taken";
  EXPECT_EQ(result.keyframes[0].first, 0u);
  EXPECT_EQ(result.keyframes[1].first, 1u);
  EXPECT_EQ(result.keyframes[2].first, 4u) << "indices into the batch";
  for (const auto& [index, mapped] : result.keyframes) EXPECT_TRUE(mapped.in_map_graph);
  EXPECT_TRUE(result.keyframes[0].second.update.keyframe_poses.empty()) << "not adjusted";
  EXPECT_TRUE(result.keyframes[1].second.update.keyframe_poses.empty()) << "not adjusted";
  // The one adjustment moves every free keyframe of the window: all but the fixed first.
  const map::KeyframeUpdate& last = result.keyframes[2].second.update;
  std::vector<std::int64_t> moved;
  for (const auto& [id, pose] : last.keyframe_poses) moved.push_back(id);
  EXPECT_EQ(moved, (std::vector<std::int64_t>{1, 2, 4}));
  EXPECT_EQ(stage_.last_closed_keyframe(), 1);
  EXPECT_TRUE(result.map_changed);
  const auto said = [&](const std::string& text) {
    for (const std::string& warning : result.warnings) {
      if (warning.find(text) != std::string::npos) return true;
    }
    return false;
  };
  EXPECT_EQ(result.falling_behind,
            "bundle adjustment falls behind: 4 keyframes added in one optimisation");
  EXPECT_TRUE(said("input skipped: keyframe 3 was measured with another camera"));
  EXPECT_FALSE(said("first keyframe received"));

  // Mode and localization's map -> odom change no map.
  const pipeline::MappingBatchResult mode =
      stage_.Take({pipeline::SlamMode::kLocalization, pipeline::LocalizationCorrectionInput{}});
  EXPECT_FALSE(mode.map_changed);
  EXPECT_EQ(stage_.mode(), pipeline::SlamMode::kLocalization);
}

TEST_F(MappingStageTest, AStageStartedWhileTheTrackingRanSaysWhatItsMapLacks) {
  const pipeline::MappingBatchResult result =
      stage_.Take({pipeline::KeyframeInput{Keyframe(7), kTestCamera}});
  EXPECT_TRUE(result.falling_behind.empty()) << "one keyframe";
  ASSERT_EQ(result.warnings.size(), 1u);
  EXPECT_NE(result.warnings[0].find("first keyframe received is 7: the keyframes before it are "
                                    "not in this map"),
            std::string::npos)
      << result.warnings[0];
  // A map whose graph cannot be rebuilt is refused with the file's name; the graph stays.
  map::SavedMap broken;
  broken.camera = kTestCamera;
  broken.edges.push_back({Edge(2, 2, 0.0), false});
  const pipeline::MappingBatchResult load =
      stage_.Take({pipeline::LoadedMapInput{broken, "broken.map"}});
  ASSERT_EQ(load.warnings.size(), 1u);
  EXPECT_NE(load.warnings[0].find("map broken.map not loaded into the pose graph"),
            std::string::npos);
  EXPECT_EQ(stage_.pose_graph().size(), 1u);
}

}  // namespace
}  // namespace stereo_fabmap_slam::test
