// A node that cannot keep real time (slow_node.test, slow_scene.yaml): the simulation slows down
// instead of piling up work, the node keeps publishing and answering, and the diagnostics warn.
// The scene is heavy enough that this holds on any machine; nothing here asserts a speed beyond
// "slower than real time".
#include <string>

#include <diagnostic_msgs/DiagnosticArray.h>
#include <gtest/gtest.h>
#include <ros/ros.h>

#include "pbd_cloth/ClothState.h"
#include "ros_test_helpers.h"

namespace {

using pbd_cloth::ClothState;
using pbd_cloth_test::node;
using pbd_cloth_test::Recorder;
using pbd_cloth_test::StateRecorder;
using pbd_cloth_test::warnsWith;

TEST(SlowNode, SlowsDownKeepsPublishingAndWarns) {
  StateRecorder states(node() + "/state");
  Recorder<diagnostic_msgs::DiagnosticArray> diagnostics("/diagnostics");

  const std::string name = node().substr(1) + ": simulation";
  diagnostic_msgs::DiagnosticArray msg;
  EXPECT_TRUE(diagnostics.waitForNext(msg, 20.0, warnsWith(name, "cannot keep real time")))
      << "no WARN 'cannot keep real time' in status '" << name << "'";

  // Still publishing, the simulated time still advancing, slower than the wall clock.
  ClothState first, later;
  ASSERT_TRUE(states.waitForNext(first, 10.0));
  ASSERT_TRUE(states.waitForNext(later, 10.0, [&](const ClothState& s) {
    return s.stats.sim_time > first.stats.sim_time && s.stats.real_time_factor > 0.0;
  }));
  EXPECT_LT(later.stats.real_time_factor, 0.9);
  EXPECT_TRUE(pbd_cloth_test::allFinite(later));

  // Services are still answered between the steps: no backlog of steps holds them up.
  EXPECT_TRUE(pbd_cloth_test::callReset(node()));
}

}  // namespace

int main(int argc, char** argv) { return pbd_cloth_test::runTests(argc, argv, "slow_node_test"); }
