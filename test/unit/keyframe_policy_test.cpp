#include "stereo_fabmap_slam/odometry/keyframe_policy.h"

#include <gtest/gtest.h>

namespace stereo_fabmap_slam::test {
namespace {

using odometry::KeyframePolicy;
using odometry::KeyframePolicyInput;
using odometry::KeyframePolicyOptions;

KeyframePolicyInput Steady() {
  KeyframePolicyInput input;
  input.tracked_points = 200;
  input.reference_tracked_points = 220;
  input.translation_since_last = 0.05;
  input.rotation_since_last_deg = 2.0;
  input.time_since_last = 0.2;
  return input;
}

TEST(KeyframePolicy, EachCriterionTriggersOnItsOwn) {
  const KeyframePolicy policy{KeyframePolicyOptions{}};
  EXPECT_FALSE(policy.Decide(Steady()).insert);

  KeyframePolicyInput input = Steady();
  input.tracked_points = 60;  // below min_tracked_points (80)
  input.reference_tracked_points = 70;
  EXPECT_EQ(policy.Decide(input).reason, "few tracked points");
  input = Steady();
  input.tracked_points = 150;  // 150 < 0.7 * 220
  EXPECT_EQ(policy.Decide(input).reason, "tracked ratio low");
  input = Steady();
  input.translation_since_last = 0.3;
  EXPECT_EQ(policy.Decide(input).reason, "translation");
  input = Steady();
  input.rotation_since_last_deg = 12.0;
  EXPECT_EQ(policy.Decide(input).reason, "rotation");
  input = Steady();
  input.time_since_last = 1.5;
  EXPECT_EQ(policy.Decide(input).reason, "interval");
  input = Steady();
  input.tracking_weak = true;
  EXPECT_EQ(policy.Decide(input).reason, "tracking weak");
}

TEST(KeyframePolicy, MinimumIntervalHoldsBackAllButWeakTracking) {
  KeyframePolicyOptions options;
  options.min_interval = 0.5;
  const KeyframePolicy policy(options);
  KeyframePolicyInput input = Steady();
  input.translation_since_last = 1.0;
  EXPECT_FALSE(policy.Decide(input).insert);
  input.time_since_last = 0.6;
  EXPECT_TRUE(policy.Decide(input).insert);
  input.time_since_last = 0.1;
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
