// When the tracking stage asks the place stage to find the camera in the map, and what it makes
// of the answers: recovery after a break of the odometry (mapping), localization at start, after
// a loss and at keyframes, and the relocalize service's requests. The tracker's results are
// made up here; the policy sees nothing else.
#include "stereo_fabmap_slam/pipeline/relocalization_policy.h"

#include <gtest/gtest.h>

namespace stereo_fabmap_slam::test {
namespace {

using pipeline::RelocalizationPolicy;
using pipeline::RelocalizationRequest;

// Recovery every n-th frame; with confirm_distance 0 the first success joins (the tests of
// the other rules), otherwise a second success that far on must agree.
relocalization::RelocalizerOptions Options(int attempt_every_n_frames,
                                           double confirm_distance = 0) {
  relocalization::RelocalizerOptions options;
  options.attempt_every_n_frames = attempt_every_n_frames;
  options.confirm_distance = confirm_distance;
  return options;
}

odometry::TrackingResult Tracked(std::int64_t reference, bool keyframe = false,
                                 bool new_segment = false) {
  odometry::TrackingResult result;
  result.state = new_segment ? odometry::TrackingState::kLost : odometry::TrackingState::kOk;
  result.reference_keyframe = reference;
  result.T_world_camera.translation() = Eigen::Vector3d(1, 2, 3);
  if (keyframe || new_segment) {
    result.keyframe.emplace();
    result.keyframe->id = reference;
    result.keyframe->starts_new_segment = new_segment;
  }
  return result;
}

odometry::TrackingResult Lost(bool map_kept) {
  odometry::TrackingResult result;
  result.state = odometry::TrackingState::kLost;
  result.map_kept = map_kept;
  return result;
}

RelocalizationRequest RequestOf(const RelocalizationPolicy::Decision& decision,
                                const odometry::TrackingResult& result) {
  RelocalizationRequest request;
  request.scope = decision.scope;
  request.add_edge = decision.add_edge;
  request.expected_T_map_camera = decision.expected_T_map_camera;
  request.from_user = decision.from_user;
  request.reference_keyframe = result.reference_keyframe;
  request.T_odom_camera = result.T_world_camera;
  return request;
}

pipeline::RelocalizationAnswer Found(std::int64_t keyframe, const Eigen::Isometry3d& T_map_camera) {
  pipeline::RelocalizationAnswer answer;
  answer.result.status = relocalization::RelocalizationStatus::kSuccess;
  answer.result.keyframe_id = keyframe;
  answer.result.inliers = 120;
  answer.map_pose_known = true;
  answer.T_map_camera = T_map_camera;
  return answer;
}

pipeline::RelocalizationAnswer NotFound() {
  pipeline::RelocalizationAnswer answer;
  answer.result.status = relocalization::RelocalizationStatus::kRansacFailed;
  answer.result.reason = "RANSAC found 3 inliers";
  return answer;
}

TEST(RelocalizationPolicy, TrackingWithoutABreakAsksNothing) {
  RelocalizationPolicy policy(Options(1));
  for (int i = 0; i < 5; ++i) {
    EXPECT_FALSE(policy.Decide(Tracked(0, i == 0), true).ask);
    EXPECT_TRUE(policy.on_map());
  }
}

TEST(RelocalizationPolicy, ALossStartsRecoveryInTheMapUntilFound) {
  RelocalizationPolicy policy(Options(1));
  ASSERT_FALSE(policy.Decide(Tracked(0, true), true).ask);
  // Lost with too few points to start a segment: no pose to find, nothing asked.
  EXPECT_FALSE(policy.Decide(Lost(false), true).ask);
  EXPECT_TRUE(policy.recovering());
  EXPECT_FALSE(policy.on_map());
  // The new segment's first keyframe: found among the map's keyframes, joined by an edge.
  const odometry::TrackingResult first = Tracked(5, true, true);
  const RelocalizationPolicy::Decision decision = policy.Decide(first, true);
  ASSERT_TRUE(decision.ask);
  EXPECT_EQ(decision.scope, RelocalizationRequest::Scope::kMap);
  EXPECT_TRUE(decision.add_edge);
  EXPECT_FALSE(decision.from_user);
  EXPECT_FALSE(policy.OnAnswer(RequestOf(decision, first), NotFound()).news.size());
  EXPECT_FALSE(policy.on_map());
  // Asked again at the next frame, found.
  const odometry::TrackingResult next = Tracked(5);
  const RelocalizationPolicy::Decision again = policy.Decide(next, true);
  ASSERT_TRUE(again.ask);
  const pipeline::RelocalizationOutcome outcome =
      policy.OnAnswer(RequestOf(again, next), Found(1, Eigen::Isometry3d::Identity()));
  EXPECT_NE(outcome.news.find("found in the map again after tracking loss against keyframe 1"),
            std::string::npos)
      << outcome.news;
  EXPECT_FALSE(outcome.T_map_odom.has_value()) << "mapping: the edge moves map -> odom";
  EXPECT_TRUE(policy.on_map());
  EXPECT_FALSE(policy.Decide(Tracked(5), true).ask);
}

// Identical corridors verify a pose metres off from one view: after a loss the first success
// is a candidate, asked about again only from 0.5 m further on; a success there that disagrees
// becomes the candidate, one that agrees joins the segment.
TEST(RelocalizationPolicy, AfterALossASecondViewFromElsewhereMustAgree) {
  RelocalizationPolicy policy(Options(1, 0.5));
  policy.Decide(Tracked(0, true), true);
  const auto at = [](double x, bool new_segment = false) {
    odometry::TrackingResult result = Tracked(5, new_segment, new_segment);
    result.T_world_camera.translation() = Eigen::Vector3d(x, 2, 3);
    return result;
  };
  const odometry::TrackingResult first = at(1.0, true);
  const RelocalizationPolicy::Decision probe = policy.Decide(first, true);
  ASSERT_TRUE(probe.ask);
  EXPECT_FALSE(probe.add_edge) << "one view proves nothing in a building of look-alikes";
  EXPECT_FALSE(probe.expected_T_map_camera.has_value());
  // Found with the camera at the map's origin: map -> odom takes (1, 2, 3) there.
  EXPECT_TRUE(policy.OnAnswer(RequestOf(probe, first), Found(1, Eigen::Isometry3d::Identity()))
                  .news.empty());
  EXPECT_TRUE(policy.recovering());
  EXPECT_FALSE(policy.on_map());
  EXPECT_FALSE(policy.Decide(at(1.4), true).ask) << "0.4 m on: the same view, nearly";

  const odometry::TrackingResult second = at(1.6);
  const RelocalizationPolicy::Decision check = policy.Decide(second, true);
  ASSERT_TRUE(check.ask);
  EXPECT_TRUE(check.add_edge);
  ASSERT_TRUE(check.expected_T_map_camera.has_value());
  EXPECT_TRUE(check.expected_T_map_camera->translation().isApprox(Eigen::Vector3d(0.6, 0, 0)));
  // Found 3 m away from where the candidate puts it (the place stage says so): a new candidate.
  Eigen::Isometry3d elsewhere = Eigen::Isometry3d::Identity();
  elsewhere.translation() = Eigen::Vector3d(3.6, 0, 0);
  pipeline::RelocalizationAnswer disagreeing = Found(2, elsewhere);
  disagreeing.agrees = false;
  const pipeline::RelocalizationOutcome replaced =
      policy.OnAnswer(RequestOf(check, second), disagreeing);
  EXPECT_NE(replaced.news.find("disagrees with the candidate against keyframe 1"),
            std::string::npos)
      << replaced.news;
  EXPECT_TRUE(policy.recovering());

  const odometry::TrackingResult third = at(2.2);
  const RelocalizationPolicy::Decision confirm = policy.Decide(third, true);
  ASSERT_TRUE(confirm.ask);
  ASSERT_TRUE(confirm.expected_T_map_camera.has_value());
  EXPECT_TRUE(confirm.expected_T_map_camera->translation().isApprox(Eigen::Vector3d(4.2, 0, 0)))
      << "the newer candidate's map -> odom";
  pipeline::RelocalizationAnswer agreeing = Found(3, *confirm.expected_T_map_camera);
  agreeing.agrees = true;
  const pipeline::RelocalizationOutcome joined =
      policy.OnAnswer(RequestOf(confirm, third), agreeing);
  EXPECT_NE(joined.news.find("as the candidate against keyframe 2 had it"), std::string::npos)
      << joined.news;
  EXPECT_FALSE(policy.recovering());
  EXPECT_TRUE(policy.on_map());
}

TEST(RelocalizationPolicy, ALoopThatJoinedTheSegmentEndsRecovery) {
  RelocalizationPolicy policy(Options(1));
  policy.Decide(Tracked(0, true), true);
  const odometry::TrackingResult first = Tracked(5, true, true);
  policy.OnAnswer(RequestOf(policy.Decide(first, true), first), NotFound());
  const odometry::TrackingResult next = Tracked(6, true);
  const RelocalizationPolicy::Decision decision = policy.Decide(next, true);
  ASSERT_TRUE(decision.ask);
  pipeline::RelocalizationAnswer joined;
  joined.already_joined = true;
  EXPECT_TRUE(policy.OnAnswer(RequestOf(decision, next), joined).news.empty());
  EXPECT_TRUE(policy.on_map());
  EXPECT_FALSE(policy.Decide(Tracked(6), true).ask);
}

// A loop may join the new segment before any relocalization does (with a candidate waiting
// for its confirmation): the frame's keyframe in the map ends recovery without a question.
TEST(RelocalizationPolicy, ALoopSeenInTheMapEndsRecoveryWithoutAsking) {
  RelocalizationPolicy policy(Options(1, 1.5));
  policy.Decide(Tracked(0, true), true);
  const odometry::TrackingResult first = Tracked(5, true, true);
  policy.OnAnswer(RequestOf(policy.Decide(first, true), first),
                  Found(1, Eigen::Isometry3d::Identity()));
  EXPECT_TRUE(policy.recovering());
  EXPECT_FALSE(policy.Decide(Tracked(6), true, /*reference_in_map=*/false).ask);
  EXPECT_FALSE(policy.on_map());
  EXPECT_FALSE(policy.Decide(Tracked(6), true, /*reference_in_map=*/true).ask);
  EXPECT_FALSE(policy.recovering());
  EXPECT_TRUE(policy.on_map());
}

// While a candidate waits: a user's request near it is a check (no edge, even to re-anchor,
// and the candidate stays); one from elsewhere is the confirmation; a break of the odometry, a
// loaded map or a change of mode drops the candidate, whose map -> odom no longer holds.
TEST(RelocalizationPolicy, ACandidateWaitsForAViewFromElsewhereWhateverTheUserAsks) {
  const auto at = [](double x, bool new_segment = false) {
    odometry::TrackingResult result = Tracked(5, new_segment, new_segment);
    result.T_world_camera.translation() = Eigen::Vector3d(x, 2, 3);
    return result;
  };
  const auto with_candidate = [&](RelocalizationPolicy* policy) {
    policy->Decide(Tracked(0, true), true);
    const odometry::TrackingResult first = at(1.0, true);
    policy->OnAnswer(RequestOf(policy->Decide(first, true), first),
                     Found(1, Eigen::Isometry3d::Identity()));
    ASSERT_TRUE(policy->recovering());
  };
  RelocalizationPolicy policy(Options(1, 1.5));
  with_candidate(&policy);
  policy.RequestFromUser(/*reanchor=*/true);
  const odometry::TrackingResult near = at(1.5);
  const RelocalizationPolicy::Decision check = policy.Decide(near, true);
  ASSERT_TRUE(check.ask);
  EXPECT_TRUE(check.from_user);
  EXPECT_FALSE(check.add_edge) << "one view, the user's or not, joins nothing";
  EXPECT_FALSE(check.expected_T_map_camera.has_value());
  Eigen::Isometry3d elsewhere = Eigen::Isometry3d::Identity();
  elsewhere.translation() = Eigen::Vector3d(9, 0, 0);
  const pipeline::RelocalizationOutcome checked =
      policy.OnAnswer(RequestOf(check, near), Found(7, elsewhere));
  ASSERT_TRUE(checked.user.has_value());
  EXPECT_TRUE(policy.recovering());
  // The candidate is still the first one: the view from 1.5 m on is checked against it.
  const RelocalizationPolicy::Decision confirm = policy.Decide(at(2.5), true);
  ASSERT_TRUE(confirm.ask);
  EXPECT_TRUE(confirm.add_edge);
  ASSERT_TRUE(confirm.expected_T_map_camera.has_value());
  EXPECT_TRUE(confirm.expected_T_map_camera->translation().isApprox(Eigen::Vector3d(1.5, 0, 0)));

  // A break while the candidate waits: the new segment's first view is a probe again.
  EXPECT_FALSE(policy.Decide(at(3.0, true), true).add_edge);
  RelocalizationPolicy loaded(Options(1, 1.5));
  with_candidate(&loaded);
  loaded.OnMapLoaded();
  EXPECT_FALSE(loaded.Decide(at(2.5), true).expected_T_map_camera.has_value());
  RelocalizationPolicy same_mode(Options(1, 1.5));
  with_candidate(&same_mode);
  same_mode.SetMode(pipeline::SlamMode::kMapping, true);  // no change: the candidate stays
  EXPECT_TRUE(same_mode.Decide(at(2.5), true).expected_T_map_camera.has_value());
}

TEST(RelocalizationPolicy, NothingToRecoverIntoBeforeTheMapHasKeyframes) {
  RelocalizationPolicy policy(Options(1));
  EXPECT_FALSE(policy.Decide(Tracked(3, true, true), false).ask)
      << "the first segment becomes the map";
  EXPECT_TRUE(policy.on_map());
}

TEST(RelocalizationPolicy, RecoveryAsksEveryNthFrameWithAPose) {
  RelocalizationPolicy policy(Options(3));
  policy.Decide(Tracked(0, true), true);
  std::vector<bool> asked;
  asked.push_back(policy.Decide(Tracked(4, true, true), true).ask);
  policy.Decide(Lost(true), true);  // no pose: not counted
  for (int i = 0; i < 5; ++i) asked.push_back(policy.Decide(Tracked(4), true).ask);
  EXPECT_EQ(asked, (std::vector<bool>{true, false, false, true, false, false}));
}

TEST(RelocalizationPolicy, AResetAndALoadedMapAreNamedWhenFoundAgain) {
  RelocalizationPolicy policy(Options(1));
  policy.Decide(Tracked(0, true), true);
  policy.OnReset();
  const odometry::TrackingResult reset = Tracked(7, true, true);
  const auto reset_decision = policy.Decide(reset, true);
  EXPECT_NE(policy.OnAnswer(RequestOf(reset_decision, reset), Found(0, {}))
                .news.find("after time went backwards"),
            std::string::npos);

  policy.OnMapLoaded();
  EXPECT_TRUE(policy.recovering()) << "this run's odometry is not in the loaded map";
  const odometry::TrackingResult next = Tracked(40);
  const auto decision = policy.Decide(next, true);
  ASSERT_TRUE(decision.ask);
  EXPECT_EQ(decision.scope, RelocalizationRequest::Scope::kMap);
  EXPECT_NE(policy.OnAnswer(RequestOf(decision, next), Found(3, {})).news.find("loading a map"),
            std::string::npos);
}

TEST(RelocalizationPolicy, LocalizationFindsTheCameraThenFollowsItAtKeyframes) {
  RelocalizationPolicy policy(Options(1));
  policy.SetMode(pipeline::SlamMode::kLocalization, true);
  const odometry::TrackingResult first = Tracked(0, true);
  const RelocalizationPolicy::Decision decision = policy.Decide(first, true);
  ASSERT_TRUE(decision.ask);
  EXPECT_EQ(decision.scope, RelocalizationRequest::Scope::kAnywhere);
  EXPECT_FALSE(decision.add_edge) << "localization never changes the map";
  EXPECT_FALSE(policy.on_map());
  Eigen::Isometry3d T_map_camera = Eigen::Isometry3d::Identity();
  T_map_camera.translation() = Eigen::Vector3d(10, 0, 0);
  const pipeline::RelocalizationOutcome outcome =
      policy.OnAnswer(RequestOf(decision, first), Found(2, T_map_camera));
  ASSERT_TRUE(outcome.T_map_odom.has_value());
  // map -> odom takes the odometry's pose onto the map's.
  EXPECT_TRUE((*outcome.T_map_odom * first.T_world_camera).isApprox(T_map_camera));
  EXPECT_NE(outcome.news.find("localized in the map"), std::string::npos);
  ASSERT_TRUE(policy.T_map_camera().has_value());
  EXPECT_TRUE(policy.T_map_camera()->isApprox(T_map_camera));
  EXPECT_FALSE(policy.Decide(Tracked(0), true).ask) << "localized: only keyframes are checked";
  EXPECT_TRUE(policy.Decide(Tracked(1, true), true).ask);
  // A break: map -> odom no longer holds; asked until found again.
  policy.Decide(Lost(false), true);
  EXPECT_FALSE(policy.on_map());
  EXPECT_TRUE(policy.Decide(Tracked(9, true, true), true).ask);
  EXPECT_TRUE(policy.Decide(Tracked(9), true).ask);
}

TEST(RelocalizationPolicy, TheEndOfLocalizationModeStartsRecovery) {
  RelocalizationPolicy policy(Options(1));
  policy.SetMode(pipeline::SlamMode::kLocalization, true);
  policy.SetMode(pipeline::SlamMode::kMapping, true);
  EXPECT_TRUE(policy.recovering());
  const auto decision = policy.Decide(Tracked(12), true);
  EXPECT_TRUE(decision.ask);
  EXPECT_TRUE(decision.add_edge);
}

TEST(RelocalizationPolicy, TheUsersRequestIsAnsweredByTheNextFrame) {
  RelocalizationPolicy policy(Options(1));
  policy.Decide(Tracked(0, true), true);
  policy.RequestFromUser(/*reanchor=*/false);
  EXPECT_TRUE(policy.user_request_pending());
  const odometry::TrackingResult frame = Tracked(0);
  const RelocalizationPolicy::Decision check = policy.Decide(frame, true);
  ASSERT_TRUE(check.ask);
  EXPECT_TRUE(check.from_user);
  EXPECT_EQ(check.scope, RelocalizationRequest::Scope::kAnywhere);
  EXPECT_FALSE(check.add_edge) << "a check of the view changes nothing";
  const pipeline::RelocalizationOutcome outcome =
      policy.OnAnswer(RequestOf(check, frame), Found(0, Eigen::Isometry3d::Identity()));
  ASSERT_TRUE(outcome.user.has_value());
  EXPECT_TRUE(outcome.user->success);
  EXPECT_EQ(outcome.user->keyframe_id, 0);
  EXPECT_FALSE(policy.user_request_pending());

  policy.RequestFromUser(/*reanchor=*/true);
  EXPECT_TRUE(policy.Decide(frame, true).add_edge) << "re-anchoring corrects map -> odom";
  policy.CancelUserRequest();

  // A frame without a pose cannot answer: the user hears why.
  policy.RequestFromUser(false);
  const RelocalizationPolicy::Decision lost = policy.Decide(Lost(true), true);
  EXPECT_FALSE(lost.ask);
  EXPECT_TRUE(lost.from_user);
  EXPECT_NE(policy.FailUserRequest(lost.failure).message.find("could not be tracked"),
            std::string::npos);
  EXPECT_FALSE(policy.user_request_pending());
}

TEST(RelocalizationPolicy, ARequestNoPlaceStageAnsweredIsAnsweredOnceAndTheRecoveryGoesOn) {
  RelocalizationPolicy policy(Options(2));
  policy.Decide(Tracked(0, true), true);
  policy.Decide(Tracked(3, false, /*new_segment=*/true), true);  // a loss: recovering
  ASSERT_TRUE(policy.recovering());
  policy.RequestFromUser(false);
  const odometry::TrackingResult frame = Tracked(3);
  const RelocalizationPolicy::Decision decision = policy.Decide(frame, true);
  ASSERT_TRUE(decision.ask);
  ASSERT_TRUE(decision.from_user);
  const pipeline::RelocalizationOutcome outcome =
      policy.OnNoAnswer(RequestOf(decision, frame), "the place stage is not running");
  ASSERT_TRUE(outcome.user.has_value());
  EXPECT_FALSE(outcome.user->success);
  EXPECT_EQ(outcome.user->message, "the place stage is not running");
  EXPECT_FALSE(outcome.T_map_odom.has_value());
  EXPECT_FALSE(policy.user_request_pending()) << "answered: the next frame is no user's";
  EXPECT_TRUE(policy.recovering()) << "nothing was found: the recovery goes on";
  // Every 2nd frame with a pose (the loss's keyframe was the first): the recovery's next
  // attempt, which no user asked for.
  const RelocalizationPolicy::Decision next = policy.Decide(frame, true);
  EXPECT_TRUE(next.ask);
  EXPECT_FALSE(next.from_user);
  EXPECT_FALSE(policy.OnNoAnswer(RequestOf(next, frame), "again").user.has_value())
      << "the recovery's own attempt has no user to answer";
  EXPECT_TRUE(policy.recovering());
}

}  // namespace
}  // namespace stereo_fabmap_slam::test
