// ~hand/wrench of cloth_node (gripper_wrench.test, test/ros/wrench_scene.yaml): the cloth hangs
// from the scripted gripper `hand` alone, so once it has come to rest the force on the gripper is
// the cloth's weight, pointing down.
#include <cmath>
#include <vector>

#include <geometry_msgs/WrenchStamped.h>
#include <gtest/gtest.h>
#include <ros/ros.h>

#include "pbd_cloth/ClothState.h"
#include "ros_test_helpers.h"

namespace {

using pbd_cloth::ClothState;
using pbd_cloth_test::node;
using pbd_cloth_test::Recorder;
using pbd_cloth_test::StateRecorder;

// After 6 s of simulated time (the damped swing has died away), the mean of 30 wrenches lies within
// 2 % of cloth.mass * |gravity| and within 1 degree of straight down; the torque is not computed.
TEST(GripperWrench, HangingClothPullsTheGripperDownWithItsWeight) {
  StateRecorder states(node() + "/state");
  Recorder<geometry_msgs::WrenchStamped> wrenches(node() + "/hand/wrench");
  ros::NodeHandle params(node());
  double mass = 0.0;
  std::vector<double> gravity;
  ASSERT_TRUE(params.getParam("cloth/mass", mass));
  ASSERT_TRUE(params.getParam("solver/gravity", gravity));
  ASSERT_EQ(gravity.size(), 3u);
  const double weight =
      mass * std::sqrt(gravity[0] * gravity[0] + gravity[1] * gravity[1] + gravity[2] * gravity[2]);

  ClothState state;
  ASSERT_TRUE(
      states.waitForNext(state, 30.0, [](const ClothState& s) { return s.stats.sim_time > 6.0; }));
  const std::size_t first = wrenches.count();
  geometry_msgs::WrenchStamped wrench;
  ASSERT_TRUE(wrenches.waitFrom(first + 29, wrench, 10.0));
  double fx = 0.0, fy = 0.0, fz = 0.0;
  const std::vector<geometry_msgs::WrenchStamped> recent = wrenches.since(first);
  ASSERT_GE(recent.size(), 30u);
  for (std::size_t k = 0; k < 30; ++k) {
    EXPECT_EQ(recent[k].header.frame_id, "world");
    fx += recent[k].wrench.force.x / 30.0;
    fy += recent[k].wrench.force.y / 30.0;
    fz += recent[k].wrench.force.z / 30.0;
  }
  const double magnitude = std::sqrt(fx * fx + fy * fy + fz * fz);
  EXPECT_NEAR(magnitude, weight, 0.02 * weight)
      << "force (" << fx << ", " << fy << ", " << fz << ") N";
  EXPECT_GT(-fz / magnitude, std::cos(1.0 * M_PI / 180.0))
      << "force (" << fx << ", " << fy << ", " << fz << ") N is not pointing down";
}

}  // namespace

int main(int argc, char** argv) {
  return pbd_cloth_test::runTests(argc, argv, "gripper_wrench_test");
}
