// A cloth crushed into itself (crushed_cloth.test, test/ros/crushed_scene.yaml): every vertex
// within the thickness of every triangle, more self-collision candidates than the search's budget
// (SelfCollision::kPairsPerElement per triangle and edge: 6768 for this 10 x 10 cloth, against
// about 50,000 pairs in the crush). The node keeps stepping, ~state counts the truncated searches
// in stats.truncated_self_collision_searches, the "simulation" status on /diagnostics warns that
// the cloth is crushed into itself, and once a normal state is set back the count is 0 again.
#include <cmath>
#include <string>

#include <diagnostic_msgs/DiagnosticArray.h>
#include <gtest/gtest.h>
#include <ros/ros.h>

#include "pbd_cloth/ClothState.h"
#include "pbd_cloth/GetState.h"
#include "pbd_cloth/SetState.h"
#include "ros_test_helpers.h"

namespace {

using pbd_cloth::ClothState;
using pbd_cloth_test::callService;
using pbd_cloth_test::node;
using pbd_cloth_test::Recorder;
using pbd_cloth_test::StateRecorder;
using pbd_cloth_test::warnsWith;

bool setState(const pbd_cloth::SimState& state) {
  pbd_cloth::SetState set;
  set.request.state = state;
  if (!callService(node() + "/set_state", set)) return false;
  EXPECT_TRUE(set.response.success) << set.response.message;
  return set.response.success;
}

TEST(CrushedCloth, SearchStopsAtItsBudgetIsCountedAndWarnedAndTheNodeKeepsStepping) {
  StateRecorder states(node() + "/state");
  Recorder<diagnostic_msgs::DiagnosticArray> diagnostics("/diagnostics");
  ClothState state;
  ASSERT_TRUE(
      states.waitForNext(state, 20.0, [](const ClothState& s) { return s.stats.sim_time > 0.2; }));
  EXPECT_EQ(state.stats.truncated_self_collision_searches, 0u) << "the swinging cloth";
  const auto restored_before = state.stats.restored_steps;
  pbd_cloth::GetState get;
  ASSERT_TRUE(callService(node() + "/get_state", get));
  const pbd_cloth::SimState saved = get.response.state;
  ASSERT_EQ(saved.positions.size(), 100u);

  // Crushed as a gripper squeezing the cloth into its fist would: every particle within 0.1 mm
  // of one point, the pinned corners held there too.
  pbd_cloth::SimState crushed = saved;
  crushed.solver_data.clear();  // positions only: the substep starts are these positions
  for (std::size_t i = 0; i < crushed.positions.size(); ++i) {
    crushed.positions[i].x = 0.2 + 1e-4 * static_cast<double>(i % 7) / 7.0;
    crushed.positions[i].y = -0.2 + 1e-4 * static_cast<double>(i % 5) / 5.0;
    crushed.positions[i].z = 0.8 + 1e-4 * static_cast<double>(i % 3) / 3.0;
    crushed.velocities[i].x = crushed.velocities[i].y = crushed.velocities[i].z = 0.0;
  }
  const std::size_t reports_before_crush = diagnostics.count();
  ASSERT_TRUE(setState(crushed));
  ASSERT_TRUE(states.waitForNext(state, 10.0, [&](const ClothState& s) {
    return s.stats.sim_time > crushed.sim_time && s.stats.truncated_self_collision_searches > 0;
  })) << "no ~state counted a truncated search after the crush";
  const double crushed_at = state.stats.sim_time;

  // The status warns, naming the crush: the node counts truncated searches between reports (one
  // a second), so a crush shorter than that shows too.
  const std::string name = node().substr(1) + ": simulation";
  diagnostic_msgs::DiagnosticArray report;
  EXPECT_TRUE(diagnostics.waitFrom(reports_before_crush, report, 5.0,
                                   warnsWith(name, "crushed into itself")))
      << "no WARN '" << name << "' saying the cloth is crushed into itself; its reports:" << [&] {
           std::string seen;
           for (const auto& m : diagnostics.since(reports_before_crush)) {
             for (const auto& status : m.status) {
               if (status.name == name) seen += "\n  " + status.message;
             }
           }
           return seen;
         }();

  // It keeps stepping, finite, and no step fails (the crushed pairs' pushes added up once threw
  // particles at hundreds of m/s, and fault recovery undid every step from then on).
  ASSERT_TRUE(states.waitForNext(
      state, 10.0, [&](const ClothState& s) { return s.stats.sim_time > crushed_at + 0.3; }));
  for (const auto& p : state.positions) ASSERT_TRUE(std::isfinite(p.x + p.y + p.z));
  EXPECT_EQ(state.stats.restored_steps, restored_before) << "steps failed after the crush";

  // A normal state set back (published at once, at its own time): after a few steps from it no
  // search hits the budget.
  std::size_t count = states.count();
  ASSERT_TRUE(setState(saved));
  ASSERT_TRUE(states.waitFrom(
      count, state, 5.0, [&](const ClothState& s) { return s.stats.sim_time == saved.sim_time; }));
  count = states.count();
  ASSERT_TRUE(states.waitFrom(count, state, 10.0, [&](const ClothState& s) {
    return s.stats.sim_time > saved.sim_time + 0.1;
  }));
  EXPECT_EQ(state.stats.truncated_self_collision_searches, 0u);
}

}  // namespace

int main(int argc, char** argv) {
  return pbd_cloth_test::runTests(argc, argv, "crushed_cloth_test");
}
