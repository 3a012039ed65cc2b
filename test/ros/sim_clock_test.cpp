// The node under /use_sim_time (sim_clock_half_speed.test, sim_clock_full_speed.test,
// time_scene.yaml). This client is the clock, at ~speed simulated seconds per wall second, and
// moves the gripper that holds the cloth's corner as a function of that clock: still, then along x
// at 0.2 m/s of simulated time for 1 s, then still. At every speed:
// - ~state stamps are the state's simulated time plus one origin (the first /clock the node saw),
//   they follow the clock (the last state after the clock stops is within a publish period of it),
//   and publish_rate is a rate of simulated time;
// - the held corner moves as commanded in simulated time: behind it by the pose follower's one
//   sample period of latency (pose_follower.h) and never ahead, with the commanded speed, so a node
//   at half speed moves the cloth no faster in simulated time than one at full speed;
// - the diagnostics say the node keeps up with /clock (a real-time factor of 0.5 is no fault when
//   /clock itself runs at half speed).
#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdio>
#include <thread>
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
using pbd_cloth_test::PosePublisher;
using pbd_cloth_test::StateRecorder;

constexpr double kClockStart = 1000.0;         // s, the first /clock
constexpr double kGripperSpeed = 0.2;          // m/s along x, in simulated time
constexpr double kMotionDuration = 1.0;        // s of simulated time
constexpr double kPosePeriod = 1.0 / 30.0;     // s of simulated time between pose messages
constexpr double kPublishPeriod = 1.0 / 30.0;  // time_scene.yaml publish_rate
constexpr int kCorner = 90;                    // held by `left` from the first step

// The commanded displacement along x at simulated time t (s).
double commanded(double t, double start) {
  return kGripperSpeed * std::min(std::max(t - start, 0.0), kMotionDuration);
}

bool holdsCorner(const ClothState& state) {
  return std::count(state.kinematic.begin(), state.kinematic.end(), kCorner) > 0;
}

// Waits (wall time) until the clock passes `time`.
bool waitForClock(ClockPublisher& clock, double time, double timeout) {
  const ros::WallTime deadline = ros::WallTime::now() + ros::WallDuration(timeout);
  while (ros::ok() && clock.now() < time) {
    if (ros::WallTime::now() > deadline) return false;
    ros::WallDuration(0.005).sleep();
  }
  return true;
}

TEST(SimClock, StampsFollowTheClockAndTheGripperMovesAsCommandedInSimulatedTime) {
  double speed = 1.0;
  ros::NodeHandle("~").getParam("speed", speed);
  ASSERT_GT(speed, 0.0);
  StateRecorder states(node() + "/state");
  pbd_cloth_test::Recorder<diagnostic_msgs::DiagnosticArray> diagnostics("/diagnostics");
  PosePublisher gripper(node() + "/left/pose");
  ASSERT_TRUE(gripper.waitForSubscriber());
  ClockPublisher clock(kClockStart, speed);

  // The node steps once /clock arrives; the first step grasps the corner.
  ClothState grasped;
  ASSERT_TRUE(states.waitForNext(grasped, 20.0, holdsCorner)) << "no state holding the corner";
  const double origin = grasped.header.stamp.toSec() - grasped.stats.sim_time;
  EXPECT_GE(origin, kClockStart - 1e-6) << "the origin is before the first /clock";
  EXPECT_LE(origin, clock.now()) << "the origin is after the clock";
  const double corner_x0 = grasped.positions[kCorner].x;
  const std::size_t first = states.count();

  // Poses at every 1/30 s tick of the clock, stamped with it, as a robot driver under
  // /use_sim_time would send them.
  const double start = clock.now() + 0.5;
  std::atomic<bool> streaming{true};
  std::thread poses([&] {
    double next_tick = std::ceil(clock.now() / kPosePeriod) * kPosePeriod;
    while (streaming && ros::ok()) {
      const double t = clock.now();
      if (t >= next_tick) {
        geometry_msgs::PoseStamped msg = pbd_cloth_test::poseStamped(
            "world", pbd_cloth_test::point(commanded(t, start), 0.0, 0.55));
        msg.header.stamp = ros::Time(t);
        gripper.publish(msg);
        while (next_tick <= t) next_tick += kPosePeriod;
      }
      ros::WallDuration(0.0005).sleep();
    }
  });
  const bool ran = waitForClock(clock, start + kMotionDuration + 0.5, 60.0);
  streaming = false;
  poses.join();
  ASSERT_TRUE(ran) << "the clock did not advance";
  clock.freeze();
  const double clock_end = clock.now();

  // With the clock stopped the node finishes what is due and then publishes nothing more.
  ClothState last;
  ASSERT_TRUE(states.waitFrom(first, last, 10.0,
                              [&](const ClothState& s) {
                                return s.header.stamp.toSec() > clock_end - kPublishPeriod - 1e-6;
                              }))
      << "no state within a publish period of the stopped clock " << clock_end;
  ros::WallDuration(0.5).sleep();
  const std::vector<ClothState> recorded = states.since(first);
  ASSERT_GE(recorded.size(), 10u);

  // Stamps: origin + simulated time, increasing, never past the clock, up to the clock.
  double previous = -1.0;
  double max_rtf = 0.0;
  for (const ClothState& s : recorded) {
    const double stamp = s.header.stamp.toSec();
    EXPECT_NEAR(stamp, origin + s.stats.sim_time, 1e-6) << "stamp is not origin + sim_time";
    EXPECT_GT(stamp, previous) << "stamps went back";
    EXPECT_LE(stamp, clock_end + 1e-6) << "a state ahead of the clock";
    previous = stamp;
    max_rtf = std::max(max_rtf, s.stats.real_time_factor);
  }
  EXPECT_GT(previous, clock_end - kPublishPeriod - 1e-6);
  // The node cannot run ahead of the clock it follows: simulated seconds per wall second stay at
  // the clock's speed (30 % for the one-second window of the factor and the clock's jitter).
  EXPECT_LE(max_rtf, 1.3 * speed) << "the node ran faster than /clock";

  // publish_rate in simulated time: one state per 1/30 s of stamps (no wall-time timer).
  const double span = recorded.back().header.stamp.toSec() - recorded.front().header.stamp.toSec();
  EXPECT_NEAR(static_cast<double>(recorded.size() - 1), span / kPublishPeriod, 2.0);

  // The held corner against the commanded motion. The pose follower reaches each sample one
  // estimated sample period after it arrives, so the corner lags the command by about one period
  // of motion (6.7 mm) and at most two (the first sample of the motion, a late sample); it is never
  // ahead by more than the 1 mm allowed for the cloth's pull on the grasp.
  const double max_lag = 2.0 * kGripperSpeed * kPosePeriod + 1e-3;
  std::vector<double> times, xs;
  double lag_sum = 0.0;
  int moving = 0;
  for (const ClothState& s : recorded) {
    const double t = s.header.stamp.toSec();
    const double dx = s.positions[kCorner].x - corner_x0;
    const double lag = commanded(t, start) - dx;
    EXPECT_GE(lag, -1e-3) << "the corner is ahead of the command at t = " << t - start;
    EXPECT_LE(lag, max_lag) << "the corner lags the command by more than two pose periods at t = "
                            << t - start;
    if (t > start + 0.2 && t < start + kMotionDuration - 0.1) {
      times.push_back(t - start);
      xs.push_back(dx);
      lag_sum += lag;
      ++moving;
    }
    if (t > start + kMotionDuration + 0.2) {
      EXPECT_NEAR(dx, kGripperSpeed * kMotionDuration, 1e-3) << "not at the end of the motion";
    }
  }
  // The speed in simulated time: a least-squares line through the moving part.
  ASSERT_GE(moving, 10);
  double mean_t = 0.0, mean_x = 0.0;
  for (int k = 0; k < moving; ++k) {
    mean_t += times[k] / moving;
    mean_x += xs[k] / moving;
  }
  double stt = 0.0, stx = 0.0;
  for (int k = 0; k < moving; ++k) {
    stt += (times[k] - mean_t) * (times[k] - mean_t);
    stx += (times[k] - mean_t) * (xs[k] - mean_x);
  }
  const double measured_speed = stx / stt;
  EXPECT_NEAR(measured_speed, kGripperSpeed, 0.05 * kGripperSpeed)
      << "the corner does not move at the commanded speed in simulated time";
  // Reported once per wall second: the run gives several reports.
  const std::string status_name = node().substr(1) + ": simulation";
  int keeping_up = 0;
  for (const auto& array : diagnostics.since(0)) {
    for (const auto& status : array.status) {
      if (status.name != status_name) continue;
      EXPECT_EQ(status.message.find("cannot keep"), std::string::npos) << status.message;
      if (status.message == "keeping up with /clock") ++keeping_up;
    }
  }
  EXPECT_GE(keeping_up, 1) << "no diagnostics status 'keeping up with /clock'";
  std::printf(
      "clock speed %.2f: %zu states, corner speed %.4f m/s (commanded %.4f), mean lag %.2f mm "
      "(one pose period of motion: %.2f mm), max real-time factor %.2f\n",
      speed, recorded.size(), measured_speed, kGripperSpeed, 1e3 * lag_sum / moving,
      1e3 * kGripperSpeed * kPosePeriod, max_rtf);
}

}  // namespace

int main(int argc, char** argv) { return pbd_cloth_test::runTests(argc, argv, "sim_clock_test"); }
