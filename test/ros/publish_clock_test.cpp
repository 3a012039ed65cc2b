// The node as the clock (~publish_clock: publish_clock.test without a limit,
// publish_clock_limited.test with ~max_real_time_factor), on the small scene:
// - /clock advances faster than wall time: more than ~min_speed_up simulated seconds per wall
//   second over two wall seconds (and, with ~max_speed_up > 0, fewer than that);
// - /clock starts at 0 and carries the states' times: ~state stamps equal stats.sim_time and each
//   is one of the /clock values; /clock only goes forward;
// - ~reset answers while the node runs free, and keeps /clock going forward: the reset state is
//   stamped at the time of the reset, not 0.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <iterator>
#include <set>
#include <vector>

#include <gtest/gtest.h>
#include <ros/ros.h>
#include <rosgraph_msgs/Clock.h>

#include "pbd_cloth/ClothState.h"
#include "ros_test_helpers.h"

namespace {

using pbd_cloth::ClothState;
using pbd_cloth_test::node;
using pbd_cloth_test::Recorder;
using pbd_cloth_test::StateRecorder;

using ClockRecorder = Recorder<rosgraph_msgs::Clock>;

// Thousands of /clock messages per second: a queue that holds several seconds of them.
constexpr uint32_t kClockQueue = 100000;
// ~state at the publish rate of a node far faster than real time (hundreds a second): with the
// default 100, a spinner busy with /clock dropped the reset's state (a fresh clone's CI, after the
// solver got faster).
constexpr uint32_t kStateQueue = 10000;

// Every stamp of `clocks` in nanoseconds, for exact look-ups.
std::set<int64_t> clockValues(const std::vector<rosgraph_msgs::Clock>& clocks) {
  std::set<int64_t> values;
  for (const auto& c : clocks) values.insert(static_cast<int64_t>(c.clock.toNSec()));
  return values;
}

// How the states whose stamp lies within the recorded /clock values compare with them.
struct StampsInClock {
  int within = 0;  // states stamped between the first and the last recorded /clock value
  int found = 0;   // of those, stamped exactly at a recorded /clock value
  // Of those not found, stamped between two recorded /clock values that are consecutive ticks
  // (no more than 1.5 typical ticks apart): no /clock message was lost there, so such a stamp is
  // not a /clock value at all.
  int between_consecutive = 0;
};

// The subscriber may lose /clock messages, which arrive at thousands a second (under load 1 % of
// them was measured lost), so a state whose stamp was not received is checked against the gap it
// falls in: a stamp in a gap left by lost messages proves nothing, one between two consecutive
// ticks is a stamp that is not a /clock value.
StampsInClock countStampsInClock(const std::vector<ClothState>& states,
                                 const std::vector<rosgraph_msgs::Clock>& clocks) {
  StampsInClock result;
  if (clocks.size() < 2) return result;
  const std::set<int64_t> values = clockValues(clocks);
  std::vector<int64_t> ticks;
  for (auto it = std::next(values.begin()); it != values.end(); ++it) {
    ticks.push_back(*it - *std::prev(it));
  }
  std::nth_element(ticks.begin(), ticks.begin() + ticks.size() / 2, ticks.end());
  const double typical_tick = static_cast<double>(ticks[ticks.size() / 2]);
  for (const ClothState& s : states) {
    const int64_t stamp = static_cast<int64_t>(s.header.stamp.toNSec());
    if (stamp < *values.begin() || stamp > *values.rbegin()) continue;
    ++result.within;
    const auto upper = values.lower_bound(stamp);
    if (*upper == stamp) {
      ++result.found;
      continue;
    }
    const int64_t lower = *std::prev(upper);
    if (static_cast<double>(*upper - lower) <= 1.5 * typical_tick) ++result.between_consecutive;
  }
  return result;
}

TEST(PublishClock, ClockRunsFasterThanWallTimeAndStampsAreItsValues) {
  double min_speed_up = 1.5, max_speed_up = 0.0;
  ros::NodeHandle("~").getParam("min_speed_up", min_speed_up);
  ros::NodeHandle("~").getParam("max_speed_up", max_speed_up);
  StateRecorder states(node() + "/state", kStateQueue);
  ClockRecorder clocks("/clock", kClockQueue);
  ClothState first;
  ASSERT_TRUE(states.waitForNext(first, 20.0)) << "no ~state";
  ASSERT_TRUE(clocks.waitForPublisher());

  const std::size_t state_from = states.count();
  const std::size_t clock_from = clocks.count();
  rosgraph_msgs::Clock c0, c1;
  ASSERT_TRUE(clocks.waitForNext(c0, 5.0));
  const ros::WallTime w0 = ros::WallTime::now();
  ros::WallDuration(2.0).sleep();
  ASSERT_TRUE(clocks.waitForNext(c1, 5.0));
  const ros::WallTime w1 = ros::WallTime::now();
  const double speed_up = (c1.clock - c0.clock).toSec() / (w1 - w0).toSec();
  std::printf("/clock ran %.2f simulated s per wall s\n", speed_up);
  EXPECT_GT(speed_up, min_speed_up) << "/clock does not run faster than wall time";
  if (max_speed_up > 0.0) {
    EXPECT_LT(speed_up, max_speed_up) << "/clock runs faster than ~max_real_time_factor";
  }

  const std::vector<ClothState> recorded = states.since(state_from);
  const std::vector<rosgraph_msgs::Clock> clock_msgs = clocks.since(clock_from);
  ASSERT_GE(recorded.size(), 10u);
  ASSERT_GE(clock_msgs.size(), 10u);
  for (std::size_t k = 1; k < clock_msgs.size(); ++k) {
    ASSERT_GT(clock_msgs[k].clock, clock_msgs[k - 1].clock) << "/clock did not go forward";
  }
  for (const ClothState& s : recorded) {
    // Origin 0: the stamp is the simulated time itself.
    EXPECT_NEAR(s.header.stamp.toSec(), s.stats.sim_time, 1e-6);
  }
  const StampsInClock stamps = countStampsInClock(recorded, clock_msgs);
  std::printf(
      "%d of %d ~state stamps found among %zu /clock values; %d of the others lie between two "
      "consecutive recorded ticks\n",
      stamps.found, stamps.within, clock_msgs.size(), stamps.between_consecutive);
  ASSERT_GE(stamps.within, 10);
  // Each state's time is published on /clock right after it. A stamp missing from the recording
  // must lie where /clock messages were lost, never between two consecutive ticks.
  EXPECT_EQ(stamps.between_consecutive, 0) << "~state stamps that are not /clock values";
  // And most are found outright (a lost message is the exception, not the rule: 98.9 % and more
  // were found on a loaded 2-core machine).
  EXPECT_GE(stamps.found, 0.9 * stamps.within) << "~state stamps are not /clock values";
}

TEST(PublishClock, ResetAnswersAndKeepsTheClockGoingForward) {
  StateRecorder states(node() + "/state", kStateQueue);
  ClockRecorder clocks("/clock", kClockQueue);
  ClothState before;
  ASSERT_TRUE(states.waitForNext(before, 20.0));
  ASSERT_TRUE(clocks.waitForPublisher());
  const std::size_t clock_from = clocks.count();
  const std::size_t state_from = states.count();
  ASSERT_TRUE(pbd_cloth_test::callReset(node())) << "~reset did not answer";

  // A state's origin is its stamp less its simulated time: 0 until the reset, the time of the
  // reset after it. The node publishes the reset state itself at once, but at thousands of states
  // a second a busy connection may drop it (the publisher keeps 10), so the first state received
  // after the reset stands for it: its origin is the reset's time.
  const double origin_before = before.header.stamp.toSec() - before.stats.sim_time;
  const auto origin = [](const ClothState& s) { return s.header.stamp.toSec() - s.stats.sim_time; };
  ClothState first_after;
  ASSERT_TRUE(states.waitFrom(state_from, first_after, 10.0, [&](const ClothState& s) {
    return origin(s) > origin_before + 1e-6;
  })) << "no state after the reset";
  EXPECT_LT(first_after.stats.sim_time, 0.5) << "the reset did not restart the simulated time";
  EXPECT_GT(origin(first_after), before.header.stamp.toSec()) << "the reset took the clock back";
  for (const ClothState& s : states.since(state_from)) {
    // The reset state itself, where it was received: at the reset's time.
    if (s.stats.sim_time < 1e-9 && origin(s) > origin_before + 1e-6) {
      EXPECT_NEAR(s.header.stamp.toSec(), origin(first_after), 1e-6);
    }
  }
  ClothState after;
  ASSERT_TRUE(
      states.waitForNext(after, 10.0, [](const ClothState& s) { return s.stats.sim_time > 0.5; }));
  EXPECT_NEAR(origin(after), origin(first_after), 1e-6) << "the origin moved after the reset";
  const std::vector<rosgraph_msgs::Clock> clock_msgs = clocks.since(clock_from);
  ASSERT_GE(clock_msgs.size(), 2u);
  for (std::size_t k = 1; k < clock_msgs.size(); ++k) {
    ASSERT_GT(clock_msgs[k].clock, clock_msgs[k - 1].clock) << "/clock went back at the reset";
  }
}

}  // namespace

int main(int argc, char** argv) {
  return pbd_cloth_test::runTests(argc, argv, "publish_clock_test");
}
