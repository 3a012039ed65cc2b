// When the node steps (step_clock.h) and which states it publishes (publish_ticks.h), driven by
// made-up ROS times: simulated time follows ROS time, catch-up is bounded, a clock that goes back
// restarts, and publishing counts simulated time.
#include <gtest/gtest.h>

#include "pbd_cloth/ros/publish_ticks.h"
#include "pbd_cloth/ros/step_clock.h"

namespace pbd_cloth {
namespace {

constexpr double kPeriod = 0.01;  // s, a 100 Hz simulation

// Runs the plan's steps on a simulated time, as the node does.
double run(const StepClock::Plan& plan, double sim_time) { return sim_time + plan.steps * kPeriod; }

TEST(StepClock, WaitsWhileRosTimeIsZero) {
  StepClock clock(StepClock::Config{kPeriod, 10});
  const StepClock::Plan plan = clock.update(ros::Time(0, 0), 0.0);
  EXPECT_TRUE(plan.waiting);
  EXPECT_EQ(plan.steps, 0);
  EXPECT_FALSE(clock.started());
}

TEST(StepClock, TheFirstTimeIsTheOriginAndStepsFollowRosTime) {
  StepClock clock(StepClock::Config{kPeriod, 10});
  double sim = 0.0;
  EXPECT_TRUE(clock.update(ros::Time(100.0), sim).started);
  EXPECT_EQ(clock.origin(), ros::Time(100.0));
  // Half a period later nothing is due; a whole one later one step; 3.5 periods on, three more.
  EXPECT_EQ(clock.update(ros::Time(100.005), sim).steps, 0);
  StepClock::Plan plan = clock.update(ros::Time(100.01), sim);
  EXPECT_EQ(plan.steps, 1);
  sim = run(plan, sim);
  plan = clock.update(ros::Time(100.045), sim);
  EXPECT_EQ(plan.steps, 3);
  sim = run(plan, sim);
  // The state is never ahead of ROS time and less than one period behind it.
  const double lag = (ros::Time(100.045) - clock.stateTime(sim)).toSec();
  EXPECT_GE(lag, 0.0);
  EXPECT_LT(lag, kPeriod);
  EXPECT_NEAR(clock.stateTime(sim).toSec(), 100.04, 1e-9);
}

TEST(StepClock, CatchUpIsBoundedAndTheOriginMovesOverTheRest) {
  StepClock clock(StepClock::Config{kPeriod, 10});
  double sim = 0.0;
  clock.update(ros::Time(100.0), sim);
  // ROS time jumps 2 s ahead: 200 steps due, 10 run, the origin moves over the other 190.
  const StepClock::Plan plan = clock.update(ros::Time(102.0), sim);
  EXPECT_EQ(plan.steps, 10);
  EXPECT_NEAR(plan.behind, 2.0, 1e-9);
  EXPECT_NEAR(plan.skipped, 1.9, 1e-9);
  EXPECT_NEAR(clock.origin().toSec(), 101.9, 1e-9);
  sim = run(plan, sim);
  // After the catch-up the state is at ROS time, and stamps went forward only.
  EXPECT_NEAR(clock.stateTime(sim).toSec(), 102.0, 1e-9);
  EXPECT_EQ(clock.update(ros::Time(102.0), sim).steps, 0);
}

TEST(StepClock, RosTimeGoingBackRestartsAtTheNewTime) {
  StepClock clock(StepClock::Config{kPeriod, 10});
  double sim = 0.0;
  clock.update(ros::Time(100.0), sim);
  sim = run(clock.update(ros::Time(100.5), sim), sim);
  const StepClock::Plan plan = clock.update(ros::Time(50.0), sim);
  EXPECT_TRUE(plan.jumped_back);
  EXPECT_NEAR(plan.jump, 50.5, 1e-9);
  EXPECT_EQ(plan.steps, 0);
  EXPECT_EQ(clock.origin(), ros::Time(50.0));
  // The caller reset the simulation: time 0 again, stepping on from the new origin.
  EXPECT_EQ(clock.update(ros::Time(50.02), 0.0).steps, 2);
}

TEST(StepClock, ARestartAtZeroWaitsForTheNextTime) {
  StepClock clock(StepClock::Config{kPeriod, 10});
  clock.update(ros::Time(100.0), 0.0);
  clock.restart(ros::Time(0, 0));
  EXPECT_FALSE(clock.started());
  EXPECT_TRUE(clock.update(ros::Time(7.0), 0.0).started);
  EXPECT_EQ(clock.origin(), ros::Time(7.0));
}

// ~set_state: simulated time jumps back to the set state's, stamps go on forward from the call.
TEST(StepClock, ASetStateIsStampedWithTheTimeOfTheCall) {
  StepClock clock(StepClock::Config{kPeriod, 10});
  double sim = 0.0;
  clock.update(ros::Time(100.0), sim);
  sim = run(clock.update(ros::Time(100.05), sim), sim);  // 5 steps: sim 0.05
  clock.continueFrom(ros::Time(100.05), 0.02);           // a state saved at 0.02 s
  sim = 0.02;
  EXPECT_EQ(clock.stateTime(sim), ros::Time(100.05));
  EXPECT_EQ(clock.update(ros::Time(100.05), sim).steps, 0);
  StepClock::Plan plan = clock.update(ros::Time(100.07), sim);
  EXPECT_EQ(plan.steps, 2);
  sim = run(plan, sim);
  EXPECT_NEAR((clock.stateTime(sim) - ros::Time(100.07)).toSec(), 0.0, 1e-9);
  // A state later than ROS time (/clock restarted at 0): stamped with its own time, and nothing is
  // due until ROS time gets there.
  clock.continueFrom(ros::Time(3.0), 10.0);
  EXPECT_EQ(clock.stateTime(10.0), ros::Time(10.0));
  EXPECT_EQ(clock.update(ros::Time(5.0), 10.0).steps, 0);
  EXPECT_EQ(clock.update(ros::Time(10.02), 10.0).steps, 2);
  // Set while no /clock has arrived: the first time seen stamps the state then current.
  StepClock waiting(StepClock::Config{kPeriod, 10});
  waiting.continueFrom(ros::Time(), 2.0);
  EXPECT_FALSE(waiting.started());
  EXPECT_TRUE(waiting.update(ros::Time(50.0), 2.0).started);
  EXPECT_EQ(waiting.stateTime(2.0), ros::Time(50.0));
}

TEST(PublishTicks, OneStateForEachTickOfSimulatedTime) {
  // 120 Hz steps, 30 Hz publishing: every fourth step, although 4/120 sums to a hair below 1/30.
  PublishTicks ticks(30.0);
  double sim = 0.0;
  int published = 0;
  for (int k = 1; k <= 120; ++k) {
    sim += 1.0 / 120.0;
    if (ticks.due(sim)) {
      ++published;
      EXPECT_EQ(k % 4, 0) << "step " << k;
    }
  }
  EXPECT_EQ(published, 30);
  // A rate that does not divide the step rate: the first state at or after each tick.
  PublishTicks odd(50.0);
  sim = 0.0;
  published = 0;
  for (int k = 1; k <= 120; ++k) {
    sim += 1.0 / 120.0;
    if (odd.due(sim)) ++published;
  }
  EXPECT_EQ(published, 50);
  // After a reset time 0 counts as published; the next tick is 1/30 s on.
  ticks.restart();
  EXPECT_FALSE(ticks.due(0.0));
  EXPECT_FALSE(ticks.due(0.02));
  EXPECT_TRUE(ticks.due(1.0 / 30.0));
  // After a set state at 2 s (or any time, earlier than the last tick included): that state
  // counts as published, the next tick follows it.
  ticks.restart(2.0);
  EXPECT_FALSE(ticks.due(2.0));
  EXPECT_TRUE(ticks.due(2.0 + 1.0 / 30.0));
}

}  // namespace
}  // namespace pbd_cloth
