#include "stereo_fabmap_slam/odometry/keyframe_policy.h"

#include <gtest/gtest.h>

namespace stereo_fabmap_slam::test {
namespace {

using odometry::KeyframeMeasures;
using odometry::KeyframePolicy;
using odometry::KeyframePolicyInput;
using odometry::KeyframePolicyOptions;

KeyframePolicyInput Steady() {
  KeyframePolicyInput input;
  input.tracked_points = 260;
  input.reference_settled_points = 220;
  input.now.settled_points = 200;
  input.now.translation = 0.05;
  input.now.rotation_deg = 2.0;
  input.now.time = 0.2;
  return input;
}

TEST(KeyframePolicy, EachCriterionTriggersOnItsOwn) {
  const KeyframePolicy policy{KeyframePolicyOptions{}};
  EXPECT_FALSE(policy.Decide(Steady()).insert);

  KeyframePolicyInput input = Steady();
  input.tracked_points = 60;  // below min_tracked_points (80)
  input.now.settled_points = 50;
  EXPECT_EQ(policy.Decide(input).reason, "few tracked points");
  input = Steady();
  input.now.settled_points = 150;  // 150 < 0.7 * 220
  EXPECT_EQ(policy.Decide(input).reason, "tracked ratio low");
  input = Steady();
  input.now.translation = 0.3;
  EXPECT_EQ(policy.Decide(input).reason, "translation");
  input = Steady();
  input.now.rotation_deg = 12.0;
  EXPECT_EQ(policy.Decide(input).reason, "rotation");
  input = Steady();
  input.now.time = 1.5;
  EXPECT_EQ(policy.Decide(input).reason, "interval");
  input = Steady();
  input.tracking_weak = true;
  EXPECT_EQ(policy.Decide(input).reason, "tracking weak");
}

TEST(KeyframePolicy, TheRatioCountsOnlySettledPoints) {
  // Many tracked points in all, but few of those the last keyframe inherited: the keyframe's own
  // new points do not hold the ratio up.
  const KeyframePolicy policy{KeyframePolicyOptions{}};
  KeyframePolicyInput input = Steady();
  input.tracked_points = 400;
  input.now.settled_points = 150;
  EXPECT_EQ(policy.Decide(input).reason, "tracked ratio low");
}

TEST(KeyframePolicy, ABoundCrossedInTheFramesToBeSkippedTakesTheKeyframeNow) {
  const KeyframePolicy policy{KeyframePolicyOptions{}};
  KeyframePolicyInput input = Steady();
  input.before_next_frame = input.now;  // nothing changes before the next frame
  EXPECT_FALSE(policy.Decide(input).insert);

  const auto ahead = [&](void (*change)(KeyframeMeasures*)) {
    KeyframePolicyInput changed = Steady();
    changed.before_next_frame = changed.now;
    change(&*changed.before_next_frame);
    return policy.Decide(changed).reason;
  };
  EXPECT_EQ(ahead([](KeyframeMeasures* m) { m->settled_points = 150; }),
            "tracked ratio low before the next tracked frame");
  EXPECT_EQ(ahead([](KeyframeMeasures* m) { m->translation = 0.3; }),
            "translation before the next tracked frame");
  EXPECT_EQ(ahead([](KeyframeMeasures* m) { m->rotation_deg = 12.0; }),
            "rotation before the next tracked frame");
  EXPECT_EQ(ahead([](KeyframeMeasures* m) { m->time = 1.5; }),
            "interval before the next tracked frame");
  // A bound crossed now is named as such.
  input.now.translation = 0.3;
  input.before_next_frame->translation = 0.4;
  EXPECT_EQ(policy.Decide(input).reason, "translation");
}

TEST(KeyframePolicy, MinimumIntervalHoldsBackAllButWeakTracking) {
  KeyframePolicyOptions options;
  options.min_interval = 0.5;
  const KeyframePolicy policy(options);
  KeyframePolicyInput input = Steady();
  input.now.translation = 1.0;
  EXPECT_FALSE(policy.Decide(input).insert);
  input.before_next_frame = input.now;
  EXPECT_FALSE(policy.Decide(input).insert);
  input.now.time = 0.6;
  EXPECT_TRUE(policy.Decide(input).insert);
  input.now.time = 0.1;
  input.tracking_weak = true;
  EXPECT_TRUE(policy.Decide(input).insert);
}

TEST(KeyframePolicy, BadOptionsAreRefused) {
  KeyframePolicyOptions options;
  options.min_tracked_ratio = 1.5;
  EXPECT_THROW(KeyframePolicy{options}, std::invalid_argument);
  options = KeyframePolicyOptions{};
  options.min_interval = 2.0;  // above max_interval
  EXPECT_THROW(KeyframePolicy{options}, std::invalid_argument);
}

}  // namespace
}  // namespace stereo_fabmap_slam::test
