// The node under /use_sim_time when /clock misbehaves (clock_jump.test, time_scene.yaml). This
// client is the clock, at real speed. In order:
// - before any /clock the node does not step (no ~state);
// - /clock going back (a looping rosbag): the node resets (simulated time back to 0, stamped at
//   the new time) and counts one rejected input;
// - /clock jumping 100 s ahead: the node keeps running without a reset, its stamps go forward
//   only, and it does not simulate the 100 s (catch-up is bounded: consecutive states stay one
//   publish period of simulated time apart while their stamps jump);
// - /clock paused: a pose in a frame tf does not know is still refused after ~tf_timeout of wall
//   time (tf2's own timeout counts ROS time and would wait for /clock forever).
#include <memory>
#include <string>
#include <vector>

#include <diagnostic_msgs/DiagnosticArray.h>
#include <gtest/gtest.h>
#include <ros/ros.h>

#include "clock_publisher.h"
#include "pbd_cloth/ClothState.h"
#include "ros_test_helpers.h"

namespace {

using pbd_cloth::ClothState;
using pbd_cloth_test::ClockPublisher;
using pbd_cloth_test::node;
using pbd_cloth_test::StateRecorder;

constexpr double kPublishPeriod = 1.0 / 30.0;  // time_scene.yaml publish_rate

// The clock of the whole client, started by the first test once it has seen the node wait.
std::unique_ptr<ClockPublisher> clock_publisher;

StateRecorder& states() {
  static StateRecorder recorder(node() + "/state");
  return recorder;
}

TEST(ClockJump, NothingStepsBeforeTheFirstClock) {
  ASSERT_TRUE(states().waitForPublisher(20.0)) << "the node does not publish ~state";
  // Connected: a state published now would arrive. A second of wall time without one.
  ros::WallDuration(1.0).sleep();
  EXPECT_EQ(states().count(), 0u) << "the node stepped without /clock";

  clock_publisher = std::make_unique<ClockPublisher>(1000.0, 1.0);
  ClothState state;
  ASSERT_TRUE(states().waitForNext(state, 10.0)) << "no ~state once /clock runs";
  EXPECT_GE(state.header.stamp.toSec(), 1000.0);
}

TEST(ClockJump, ClockGoingBackResetsAndCountsOneRejectedInput) {
  ASSERT_TRUE(clock_publisher);
  ClothState before;
  ASSERT_TRUE(states().waitForNext(before, 10.0,
                                   [](const ClothState& s) { return s.stats.sim_time > 0.5; }));
  const std::size_t from = states().count();
  clock_publisher->jumpTo(500.0);

  ClothState reset;
  ASSERT_TRUE(states().waitFrom(from, reset, 10.0, [](const ClothState& s) {
    return s.stats.sim_time < 1e-9;
  })) << "no reset state (sim_time 0) after /clock went back";
  EXPECT_EQ(reset.stats.rejected_inputs, before.stats.rejected_inputs + 1);
  EXPECT_GE(reset.header.stamp.toSec(), 500.0);
  EXPECT_LT(reset.header.stamp.toSec(), 501.0);

  // On from the new time: stamps are the new origin plus simulated time.
  ClothState after;
  ASSERT_TRUE(states().waitForNext(after, 10.0,
                                   [](const ClothState& s) { return s.stats.sim_time > 0.3; }));
  EXPECT_NEAR(after.header.stamp.toSec() - after.stats.sim_time, reset.header.stamp.toSec(), 1e-6);
  EXPECT_EQ(after.stats.rejected_inputs, reset.stats.rejected_inputs);
}

TEST(ClockJump, ClockJumpingAheadKeepsRunningWithStampsGoingForward) {
  ASSERT_TRUE(clock_publisher);
  ClothState before;
  ASSERT_TRUE(states().waitForNext(before, 10.0));
  const std::size_t from = states().count() - 1;
  const double target = clock_publisher->now() + 100.0;
  clock_publisher->jumpTo(target);

  ClothState after;
  ASSERT_TRUE(states().waitFrom(from, after, 10.0, [&](const ClothState& s) {
    return s.header.stamp.toSec() >= target;
  })) << "no state stamped after the jump";
  // A second of states past the jump.
  ASSERT_TRUE(states().waitForNext(
      after, 10.0, [&](const ClothState& s) { return s.header.stamp.toSec() >= target + 1.0; }));

  const std::vector<ClothState> recorded = states().since(from);
  ASSERT_GE(recorded.size(), 3u);
  bool crossed = false;
  for (std::size_t k = 1; k < recorded.size(); ++k) {
    const ClothState& a = recorded[k - 1];
    const ClothState& b = recorded[k];
    EXPECT_GT(b.header.stamp, a.header.stamp) << "stamps went back";
    EXPECT_GT(b.stats.sim_time, a.stats.sim_time) << "the node reset on a jump ahead";
    EXPECT_EQ(b.stats.rejected_inputs, before.stats.rejected_inputs);
    // Published once per period of simulated time, also across the jump: the 100 s were not
    // simulated.
    EXPECT_NEAR(b.stats.sim_time - a.stats.sim_time, kPublishPeriod, 1e-6);
    if (b.header.stamp.toSec() - a.header.stamp.toSec() > 50.0) crossed = true;
  }
  EXPECT_TRUE(crossed) << "no pair of consecutive states across the jump";
}

// The node's count of rejected inputs in its diagnostics ("<node>: inputs"), or -1.
int rejectedInDiagnostics(const diagnostic_msgs::DiagnosticArray& array) {
  const std::string name = node().substr(1) + ": inputs";
  for (const auto& status : array.status) {
    if (status.name != name) continue;
    for (const auto& value : status.values) {
      if (value.key == "rejected inputs") return std::stoi(value.value);
    }
  }
  return -1;
}

TEST(ClockJump, APoseWaitingForTfIsRefusedWhileTheClockIsPaused) {
  ASSERT_TRUE(clock_publisher);
  pbd_cloth_test::Recorder<diagnostic_msgs::DiagnosticArray> diagnostics("/diagnostics");
  pbd_cloth_test::PosePublisher gripper(node() + "/left/pose");
  ASSERT_TRUE(gripper.waitForSubscriber());
  ClothState state;
  ASSERT_TRUE(states().waitForNext(state, 10.0));
  clock_publisher->freeze();
  // The diagnostics come on a wall timer, so they report while simulated time stands still.
  diagnostic_msgs::DiagnosticArray array;
  ASSERT_TRUE(diagnostics.waitForNext(array, 10.0, [](const diagnostic_msgs::DiagnosticArray& a) {
    return rejectedInDiagnostics(a) >= 0;
  }));
  const int before = rejectedInDiagnostics(array);
  gripper.publish(pbd_cloth_test::poseStamped("nowhere", pbd_cloth_test::point(0.0, 0.0, 0.5)));
  EXPECT_TRUE(diagnostics.waitForNext(array, 10.0, [&](const diagnostic_msgs::DiagnosticArray& a) {
    return rejectedInDiagnostics(a) == before + 1;
  })) << "the pose in an unknown frame was not refused while /clock was paused";
  clock_publisher->resume();
}

}  // namespace

int main(int argc, char** argv) {
  const int result = pbd_cloth_test::runTests(argc, argv, "clock_jump_test");
  clock_publisher.reset();
  return result;
}
