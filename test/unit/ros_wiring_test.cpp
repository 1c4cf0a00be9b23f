// The nodelets' plumbing without a ROS graph: the bounded queue between the image callbacks and
// the tracking thread accounts for every pair (tracked, refused or skipped), the LoopDetector's
// pairing of keyframes with the Backend's answers in either order, and the relocalize service's
// timeout.
#include <chrono>
#include <cmath>
#include <limits>
#include <thread>

#include <gtest/gtest.h>
#include <boost/make_shared.hpp>

#include "backend_wiring.h"
#include "place_wiring.h"
#include "tracker_outputs.h"
#include "tracker_wiring.h"
#include "transform_repeater.h"

namespace stereo_fabmap_slam::test {
namespace {

sensor_msgs::ImageConstPtr ImageAt(double seconds) {
  auto image = boost::make_shared<sensor_msgs::Image>();
  image->header.stamp.fromSec(seconds);
  return image;
}

TEST(PairQueue, EveryPairReceivedIsCountedEvenBeforeTheCalibration) {
  pipeline::InputMonitor monitor{pipeline::InputMonitorOptions()};  // no calibration yet
  ros_wiring::PairQueue queue;
  queue.Configure(/*capacity=*/4, /*catch_up_gap=*/0.0, &monitor);
  // Ten pairs at 20 Hz while the tracker takes none: four wait, six are dropped (and counted).
  for (int i = 0; i < 10; ++i) queue.Push(ImageAt(0.05 * i), ImageAt(0.05 * i));
  EXPECT_EQ(monitor.counts().received, 10u);
  EXPECT_EQ(monitor.counts().skipped, 6u);
  std::vector<pipeline::InputEvent> events;
  const std::optional<ros_wiring::ImagePair> first = queue.Take(&events);
  ASSERT_TRUE(first.has_value());
  EXPECT_EQ(first->arrival, 1u) << "the first pair is taken as it comes";
  // The rest of the backlog: the queue passes over what it must to keep the gaps even; every
  // pair it passes over is counted.
  std::uint64_t taken = 1;
  while (monitor.counts().skipped + taken < 10) {
    ASSERT_TRUE(queue.Take(&events).has_value());
    ++taken;
  }
  EXPECT_EQ(taken + monitor.counts().skipped, monitor.counts().received);
  queue.Stop();
  EXPECT_FALSE(queue.Take(&events).has_value()) << "stopping ends the wait";
}

stereo_fabmap_slam::KeyframeConstPtr KeyframeMessage(std::uint64_t id) {
  auto keyframe = boost::make_shared<stereo_fabmap_slam::Keyframe>();
  keyframe->id = id;
  return keyframe;
}

stereo_fabmap_slam::KeyframeUpdateConstPtr UpdateMessage(std::uint64_t id) {
  auto update = boost::make_shared<stereo_fabmap_slam::KeyframeUpdate>();
  update->keyframe_id = id;
  return update;
}

TEST(KeyframePairing, EachKeyframeMeetsItsAnswerInEitherOrder) {
  ros_wiring::KeyframePairing pairing;
  pairing.AddKeyframe(KeyframeMessage(0));  // keyframe first
  pairing.AddUpdate(UpdateMessage(0));
  pairing.AddUpdate(UpdateMessage(1));  // answer first
  pairing.AddKeyframe(KeyframeMessage(1));
  for (std::uint64_t id = 0; id < 2; ++id) {
    const std::optional<ros_wiring::KeyframePairing::Pair> pair = pairing.Take();
    ASSERT_TRUE(pair.has_value());
    ASSERT_TRUE(pair->keyframe);
    EXPECT_EQ(pair->keyframe->id, id);
    EXPECT_EQ(pair->update->keyframe_id, id);
  }
  // Keyframe 2 never answered (no Backend then), 4's answer without its keyframe (this nodelet
  // was not running): 3 is paired, 2 dropped; 4 is handed over alone once a later keyframe came.
  pairing.AddKeyframe(KeyframeMessage(2));
  pairing.AddUpdate(UpdateMessage(4));
  pairing.AddKeyframe(KeyframeMessage(5));
  const std::optional<ros_wiring::KeyframePairing::Pair> alone = pairing.Take();
  ASSERT_TRUE(alone.has_value());
  EXPECT_FALSE(alone->keyframe) << "its keyframe never came";
  EXPECT_EQ(alone->update->keyframe_id, 4u);
  pairing.AddUpdate(UpdateMessage(5));
  const std::optional<ros_wiring::KeyframePairing::Pair> next = pairing.Take();
  ASSERT_TRUE(next.has_value() && next->keyframe);
  EXPECT_EQ(next->keyframe->id, 5u) << "keyframe 2, never answered, was dropped";
  pairing.Stop();
  EXPECT_FALSE(pairing.Take().has_value());
}

TEST(RelocalizeTimeout, ANumberOfSecondsUpToAMinuteOrARefusal) {
  EXPECT_EQ(ros_wiring::RelocalizeTimeout(0.0), 1.0) << "0: the default second";
  EXPECT_EQ(ros_wiring::RelocalizeTimeout(2.5), 2.5);
  EXPECT_EQ(ros_wiring::RelocalizeTimeout(60.0), 60.0);
  for (const double refused : {-1.0, 60.5, 3600.0, std::numeric_limits<double>::quiet_NaN(),
                               std::numeric_limits<double>::infinity()}) {
    EXPECT_FALSE(ros_wiring::RelocalizeTimeout(refused).has_value()) << refused;
  }
}

// Lockstep's cue: the Backend's word on the keyframe, its loop detection, and every
// relocalization edge the LoopDetector sent it (the graph counts the edges it received).
TEST(MappingProgress, LockstepWaitsForTheKeyframeItsLoopDetectionAndEveryEdgeSent) {
  ros_wiring::MappingProgress progress;
  EXPECT_TRUE(progress.WaitFor(-1, true, 0.0)) << "a frame without a keyframe waits for nothing";
  EXPECT_FALSE(progress.WaitFor(3, false, 0.01)) << "no update of keyframe 3 yet";
  progress.OnUpdate(3);
  EXPECT_TRUE(progress.WaitFor(3, false, 0.0));
  EXPECT_FALSE(progress.WaitFor(3, true, 0.01)) << "its loop detection not applied yet";
  stereo_fabmap_slam::MapGraph graph;
  graph.last_closed_keyframe_id = 3;
  progress.OnGraph(graph);
  EXPECT_TRUE(progress.WaitFor(3, true, 0.0));
  progress.OnRelocalizationEdgeSent();
  EXPECT_FALSE(progress.WaitFor(3, true, 0.01)) << "the edge has not reached the Backend";
  graph.relocalization_edges_received = 1;
  progress.OnGraph(graph);
  EXPECT_TRUE(progress.WaitFor(3, true, 0.0));
}

// After the bag's end the nodelets say their last transforms again, a nanosecond later each
// time, so that tf tools started then find the frames and listeners that have them see no
// repeated stamp.
TEST(TransformRepeater, TheLastTransformsAgainOnceAPeriodPassedWithoutNews) {
  ros_wiring::TransformRepeater repeater(1.0);
  const ros::Time stopped(52, 0);  // the bag's clock, stopped 2 s after the last image
  EXPECT_TRUE(repeater.Due(100.0, stopped).empty()) << "nothing sent, nothing to repeat";
  geometry_msgs::TransformStamped base;
  base.child_frame_id = "base_link";
  base.header.stamp = ros::Time(50, 0);
  base.transform.translation.x = 1.5;
  base.transform.rotation.w = 1;
  repeater.Sent(base, 100.0);
  EXPECT_TRUE(repeater.Due(100.9, stopped).empty()) << "news within the period: a camera streams";
  std::vector<geometry_msgs::TransformStamped> due = repeater.Due(101.0, stopped);
  ASSERT_EQ(due.size(), 1u);
  EXPECT_EQ(due[0].header.stamp, stopped) << "at the clock, where the other nodelets' are";
  EXPECT_EQ(due[0].child_frame_id, "base_link");
  EXPECT_EQ(due[0].transform.translation.x, 1.5);
  EXPECT_TRUE(repeater.Due(101.5, stopped).empty()) << "at most once a period";
  due = repeater.Due(102.0, stopped);
  ASSERT_EQ(due.size(), 1u);
  EXPECT_EQ(due[0].header.stamp, ros::Time(52, 1)) << "every repeat a new stamp";
  // A second frame, and news: repeats wait a period from the news, then carry both.
  geometry_msgs::TransformStamped map = base;
  map.child_frame_id = "odom";
  map.header.stamp = ros::Time(52, 1);
  repeater.Sent(map, 102.5);
  base.header.stamp = ros::Time(52, 0);
  repeater.Sent(base, 102.6);
  EXPECT_TRUE(repeater.Due(103.5, stopped).empty());
  due = repeater.Due(103.6, stopped);
  ASSERT_EQ(due.size(), 2u);
  for (const geometry_msgs::TransformStamped& transform : due) {
    EXPECT_EQ(transform.header.stamp,
              transform.child_frame_id == "base_link" ? ros::Time(52, 1) : ros::Time(52, 2));
  }
}

// The Backend's inputs reach its stage in the order they arrived, all that waited at once.
TEST(ArrivalQueue, HandsOverEverythingThatWaitedInArrivalOrder) {
  ros_wiring::BackendQueue queue;
  auto keyframe = boost::make_shared<stereo_fabmap_slam::Keyframe>();
  keyframe->header.stamp = ros::Time(12, 5);
  queue.Push(pipeline::SlamMode::kLocalization);
  queue.Push(stereo_fabmap_slam::KeyframeConstPtr(keyframe));
  queue.Push(ros_wiring::MapFileLoaded{"/nonexistent/map.bin"});
  const std::optional<std::deque<ros_wiring::BackendInput>> waiting = queue.TakeAll();
  ASSERT_TRUE(waiting.has_value());
  ASSERT_EQ(waiting->size(), 3u);
  EXPECT_EQ(std::get<pipeline::SlamMode>(ros_wiring::ToMappingInput((*waiting)[0])),
            pipeline::SlamMode::kLocalization);
  EXPECT_EQ(ros_wiring::HeaderOf((*waiting)[1]).stamp, ros::Time(12, 5))
      << "a keyframe's update carries its header";
  EXPECT_TRUE(ros_wiring::HeaderOf((*waiting)[0]).stamp.isZero());
  // A map file gone since the LoopDetector took it: the Backend logs and skips the input.
  EXPECT_THROW(ros_wiring::ToMappingInput((*waiting)[2]), std::exception);
  // Stopping wakes a worker that waits.
  // A timed wait returns what waits, nothing after the timeout.
  queue.Push(pipeline::SlamMode::kMapping);
  const auto timed = queue.TakeAll(std::chrono::milliseconds(0));
  ASSERT_TRUE(timed.has_value());
  EXPECT_EQ(timed->size(), 1u);
  const auto nothing = queue.TakeAll(std::chrono::milliseconds(1));
  ASSERT_TRUE(nothing.has_value());
  EXPECT_TRUE(nothing->empty());
  std::thread worker([&] { EXPECT_FALSE(queue.TakeAll().has_value()); });
  queue.Stop();
  worker.join();
  EXPECT_FALSE(queue.TakeAll(std::chrono::seconds(1)).has_value()) << "stopped: no wait";
  // What came after the stop is still there for the end of a run.
  queue.Push(pipeline::SlamMode::kMapping);
  queue.Push(pipeline::SlamMode::kLocalization);
  EXPECT_EQ(queue.TakeRemaining().size(), 2u);
  EXPECT_TRUE(queue.TakeRemaining().empty());
}

}  // namespace
}  // namespace stereo_fabmap_slam::test
