// Two cloth_nodes in two namespaces (two_nodes.test): grasping, bad input and reconfiguring node
// a leave node b untouched, and each reports diagnostics under its own name.
#include <algorithm>
#include <limits>
#include <set>
#include <string>

#include <diagnostic_msgs/DiagnosticArray.h>
#include <dynamic_reconfigure/Reconfigure.h>
#include <gtest/gtest.h>
#include <ros/ros.h>

#include "pbd_cloth/ClothState.h"
#include "ros_test_helpers.h"

namespace {

using pbd_cloth::ClothState;
using pbd_cloth_test::point;
using pbd_cloth_test::PosePublisher;
using pbd_cloth_test::poseStamped;
using pbd_cloth_test::Recorder;
using pbd_cloth_test::StateRecorder;

constexpr int kCorner = 90;  // bottom-left corner of the hanging 10 x 10 cloth

std::string param(const std::string& name) {
  std::string value;
  EXPECT_TRUE(ros::NodeHandle("~").getParam(name, value)) << "~" << name;
  return value;
}

const std::string& nodeA() {
  static const std::string name = param("node_a");
  return name;
}

const std::string& nodeB() {
  static const std::string name = param("node_b");
  return name;
}

bool holds(const ClothState& state, int index) {
  return std::count(state.kinematic.begin(), state.kinematic.end(), index) > 0;
}

TEST(TwoNodes, AGraspInOneDoesNotShowInTheOther) {
  StateRecorder states_a(nodeA() + "/state");
  StateRecorder states_b(nodeB() + "/state");
  PosePublisher gripper_a(nodeA() + "/left/pose");
  ASSERT_TRUE(gripper_a.waitForSubscriber());
  ClothState a, b;
  ASSERT_TRUE(states_a.waitForNext(a, 10.0));
  ASSERT_TRUE(states_b.waitForNext(b, 10.0));
  const double b_corner_z = b.positions[kCorner].z;

  const geometry_msgs::Point corner = a.positions[kCorner];
  gripper_a.publish(poseStamped("world", corner));
  ros::WallDuration(1.0).sleep();  // the follower arrives within its default period (0.1 s)
  ASSERT_TRUE(pbd_cloth_test::callGrasp(nodeA() + "/left/grasp", true));
  const geometry_msgs::Point raised = point(corner.x, corner.y, corner.z + 0.2);
  gripper_a.stream("world", corner, raised, 0.5);
  ASSERT_TRUE(states_a.waitForNext(a, 5.0, [&](const ClothState& s) {
    return holds(s, kCorner) && s.positions[kCorner].z > raised.z - 1e-3;
  }));

  ASSERT_TRUE(states_b.waitForNext(b, 5.0));
  EXPECT_FALSE(holds(b, kCorner)) << "node b grasped too";
  EXPECT_LT(b.positions[kCorner].z, b_corner_z + 0.05) << "node b's corner was lifted too";
  EXPECT_TRUE(pbd_cloth_test::callGrasp(nodeA() + "/left/grasp", false));
}

TEST(TwoNodes, BadInputToOneIsCountedByThatOneOnly) {
  StateRecorder states_a(nodeA() + "/state");
  StateRecorder states_b(nodeB() + "/state");
  PosePublisher gripper_a(nodeA() + "/left/pose");
  ASSERT_TRUE(gripper_a.waitForSubscriber());
  ClothState a, b;
  ASSERT_TRUE(states_a.waitForNext(a, 10.0));
  const unsigned before = a.stats.rejected_inputs;
  gripper_a.publish(
      poseStamped("world", point(std::numeric_limits<double>::quiet_NaN(), 0.0, 0.0)));
  ASSERT_TRUE(states_a.waitForNext(
      a, 5.0, [before](const ClothState& s) { return s.stats.rejected_inputs > before; }));
  ASSERT_TRUE(states_b.waitForNext(b, 5.0));
  EXPECT_EQ(b.stats.rejected_inputs, 0u);
}

TEST(TwoNodes, ReconfiguringOneLeavesTheOther) {
  StateRecorder states_a(nodeA() + "/state");
  StateRecorder states_b(nodeB() + "/state");
  ClothState a, b;
  ASSERT_TRUE(states_b.waitForNext(b, 10.0));
  const unsigned b_substeps = b.stats.substeps;
  const int wanted = static_cast<int>(b_substeps) + 3;

  dynamic_reconfigure::Reconfigure srv;
  dynamic_reconfigure::IntParameter substeps;
  substeps.name = "substeps";
  substeps.value = wanted;
  srv.request.config.ints.push_back(substeps);
  ASSERT_TRUE(pbd_cloth_test::callService(nodeA() + "/set_parameters", srv));
  ASSERT_TRUE(states_a.waitForNext(a, 5.0, [wanted](const ClothState& s) {
    return s.stats.substeps == static_cast<unsigned>(wanted);
  }));
  ASSERT_TRUE(states_b.waitForNext(b, 5.0));
  EXPECT_EQ(b.stats.substeps, b_substeps);
}

TEST(TwoNodes, EachReportsDiagnosticsUnderItsOwnName) {
  Recorder<diagnostic_msgs::DiagnosticArray> diagnostics("/diagnostics");
  const std::string name_a = nodeA().substr(1) + ": simulation";
  const std::string name_b = nodeB().substr(1) + ": simulation";
  std::set<std::string> seen;
  diagnostic_msgs::DiagnosticArray msg;
  EXPECT_TRUE(diagnostics.waitForNext(msg, 10.0,
                                      [&](const diagnostic_msgs::DiagnosticArray& m) {
                                        for (const auto& status : m.status)
                                          seen.insert(status.name);
                                        return seen.count(name_a) > 0 && seen.count(name_b) > 0;
                                      }))
      << "expected statuses '" << name_a << "' and '" << name_b << "'";
}

}  // namespace

int main(int argc, char** argv) { return pbd_cloth_test::runTests(argc, argv, "two_nodes_test"); }
