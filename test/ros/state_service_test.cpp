// ~get_state and ~set_state of cloth_node (state_service.test, test/ros/small_scene.yaml): a state
// got mid-swing and set back after the cloth moved on is the next ~state exactly (float64 all the
// way); a state with a particle too few, a NaN or another frame is refused with the reason,
// counted as a rejected input, and the node carries on from where it was.
#include <cmath>
#include <limits>
#include <string>

#include <gtest/gtest.h>
#include <ros/ros.h>

#include "pbd_cloth/ClothState.h"
#include "pbd_cloth/GetState.h"
#include "pbd_cloth/SetState.h"
#include "ros_test_helpers.h"

namespace {

using pbd_cloth::ClothState;
using pbd_cloth_test::callService;
using pbd_cloth_test::distance;
using pbd_cloth_test::node;
using pbd_cloth_test::StateRecorder;

bool getState(pbd_cloth::SimState& state) {
  pbd_cloth::GetState srv;
  if (!callService(node() + "/get_state", srv)) return false;
  state = srv.response.state;
  return true;
}

double largestMove(const ClothState& state, const pbd_cloth::SimState& saved) {
  double largest = 0.0;
  for (std::size_t i = 0; i < state.positions.size(); ++i) {
    largest = std::max(largest, distance(state.positions[i], saved.positions[i]));
  }
  return largest;
}

TEST(StateService, SetStateBringsTheSavedPositionsBackExactly) {
  StateRecorder states(node() + "/state");
  ClothState state;
  ASSERT_TRUE(
      states.waitForNext(state, 20.0, [](const ClothState& s) { return s.stats.sim_time > 0.3; }));
  pbd_cloth::SimState saved;
  ASSERT_TRUE(getState(saved));
  ASSERT_EQ(saved.positions.size(), 100u);
  ASSERT_EQ(saved.velocities.size(), 100u);
  EXPECT_EQ(saved.header.frame_id, "world");
  EXPECT_FALSE(saved.solver_data.empty());

  // The cloth swings on: well away from the saved state.
  ASSERT_TRUE(states.waitForNext(
      state, 10.0, [&](const ClothState& s) { return s.stats.sim_time > saved.sim_time + 0.5; }));
  ASSERT_GT(largestMove(state, saved), 0.05) << "the cloth did not move: the test proves nothing";
  const ros::Time before_stamp = state.header.stamp;

  const std::size_t count = states.count();
  pbd_cloth::SetState set;
  set.request.state = saved;
  ASSERT_TRUE(callService(node() + "/set_state", set));
  EXPECT_TRUE(set.response.success) << set.response.message;
  // The node publishes the set state at once: the saved positions, every bit.
  ASSERT_TRUE(states.waitFrom(
      count, state, 5.0, [&](const ClothState& s) { return s.stats.sim_time == saved.sim_time; }));
  EXPECT_EQ(state.stats.sim_time, saved.sim_time);
  ASSERT_EQ(state.positions.size(), saved.positions.size());
  for (std::size_t i = 0; i < state.positions.size(); ++i) {
    EXPECT_EQ(state.positions[i].x, saved.positions[i].x) << i;
    EXPECT_EQ(state.positions[i].y, saved.positions[i].y) << i;
    EXPECT_EQ(state.positions[i].z, saved.positions[i].z) << i;
    EXPECT_EQ(state.velocities[i].x, saved.velocities[i].x) << i;
    EXPECT_EQ(state.velocities[i].z, saved.velocities[i].z) << i;
  }
  // Simulated time jumped back, stamps did not.
  EXPECT_GE(state.header.stamp, before_stamp);
  // And it steps on from there.
  ASSERT_TRUE(states.waitForNext(
      state, 5.0, [&](const ClothState& s) { return s.stats.sim_time > saved.sim_time + 0.1; }));
  EXPECT_LT(state.stats.sim_time, saved.sim_time + 2.0);
}

// Refused, with `field` in the message, counted, and the node goes on where it was.
void expectRefused(const pbd_cloth::SimState& bad, const std::string& field) {
  StateRecorder states(node() + "/state");
  ClothState before;
  ASSERT_TRUE(states.waitForNext(before, 10.0));
  pbd_cloth::SetState set;
  set.request.state = bad;
  ASSERT_TRUE(callService(node() + "/set_state", set));
  EXPECT_FALSE(set.response.success);
  EXPECT_NE(set.response.message.find(field), std::string::npos) << set.response.message;
  ClothState after;
  ASSERT_TRUE(states.waitForNext(after, 5.0, [&](const ClothState& s) {
    return s.stats.rejected_inputs > before.stats.rejected_inputs;
  }));
  EXPECT_EQ(after.stats.rejected_inputs, before.stats.rejected_inputs + 1);
  // No jump: simulated time went on from where it was, not to the refused state's.
  EXPECT_GE(after.stats.sim_time, before.stats.sim_time);
  EXPECT_LT(after.stats.sim_time, before.stats.sim_time + 2.0);
  EXPECT_EQ(after.positions.size(), 100u);
}

TEST(StateService, StateThatDoesNotFitIsRefusedAndChangesNothing) {
  pbd_cloth::SimState good;
  ASSERT_TRUE(getState(good));
  // Far back in simulated time, so a state set by mistake would show as a jump.
  good.sim_time = 0.0;

  pbd_cloth::SimState bad = good;
  bad.positions.pop_back();
  expectRefused(bad, "positions: 99 given, the scene has 100 particles");

  bad = good;
  bad.velocities[5].y = std::numeric_limits<double>::quiet_NaN();
  expectRefused(bad, "velocities[5]: not finite");

  bad = good;
  bad.header.frame_id = "map";
  expectRefused(bad, "header.frame_id");

  bad = good;
  bad.solver_data = {1, 2, 3};
  expectRefused(bad, "solver_data");
}

}  // namespace

int main(int argc, char** argv) {
  return pbd_cloth_test::runTests(argc, argv, "state_service_test");
}
