// Sleeping (solver.sleep_speed, Simulation::step): a towel at rest on a table sleeps, costs no
// solve while it sleeps, and wakes for everything that could move it.
#include <gtest/gtest.h>

#include <cmath>

#include "collision_scenes.h"
#include "pbd_cloth/sim/simulation.h"
#include "test_scenes.h"

namespace pbd_cloth {
namespace {

// config/towel_on_table.yaml in small: a 16 x 16 towel dropped 2 cm onto a table, with a gripper
// above its middle and a ball far to the side.
SceneConfig towelScene() {
  SceneConfig scene = test::clothScene(16, 16, 0.04, Method::kXpbd);
  scene.cloth.origin = Vec3(-0.3, 0.3, 0.82);
  scene.cloth.pinned.clear();
  scene.cloth.self_collision = false;
  scene.cloth.bend_compliance = 10.0;
  scene.solver.damping = 0.5;
  scene.solver.substeps = 10;
  scene.solver.sleep_speed = 0.005;
  scene.solver.sleep_time = 0.5;
  ObstacleConfig table;
  table.name = "table";
  table.shape = ShapeType::kBox;
  table.size = Vec3(1.2, 1.2, 0.05);
  table.pose = test::makePose(Vec3(0.0, 0.0, 0.775));
  ObstacleConfig ball;
  ball.name = "ball";
  ball.radius = 0.1;
  ball.pose = test::makePose(Vec3(3.0, 0.0, 1.0));
  scene.obstacles = {table, ball};
  GripperConfig gripper;
  gripper.name = "hand";
  gripper.radius = 0.05;
  scene.grippers = {gripper};
  return scene;
}

// Steps until the scene sleeps (at most 5 s); fails the test if it never does.
void stepUntilAsleep(Simulation& sim) {
  for (int step = 0; step < 300 && !sim.sleeping().asleep(); ++step) sim.step();
  ASSERT_TRUE(sim.sleeping().asleep()) << "the towel did not fall asleep within 5 s";
}

TEST(Sleeping, ATowelAtRestSleepsAndHoldsStill) {
  Simulation sim(towelScene());
  stepUntilAsleep(sim);
  const Vec3Array rest = sim.particles().position;
  const double slept_before = sim.sleeping().sleptSteps();
  const double t0 = sim.time();
  for (int step = 0; step < 60; ++step) sim.step();
  EXPECT_TRUE(sim.sleeping().asleep());
  EXPECT_EQ(sim.sleeping().sleptSteps() - slept_before, 60);
  EXPECT_NEAR(sim.time() - t0, 1.0, 1e-9);  // time goes on
  EXPECT_EQ(sim.particles().position, rest);
  EXPECT_EQ(sim.stats().iterations, 0);  // no solve in a slept step
  // It lies on the table: 0.8 m top plus its thickness, not below.
  for (const Vec3& x : rest) EXPECT_NEAR(x.z(), 0.8 + 0.005, 2e-3);
}

TEST(Sleeping, OffByDefault) {
  SceneConfig scene = towelScene();
  scene.solver.sleep_speed = 0.0;
  Simulation sim(scene);
  for (int step = 0; step < 180; ++step) sim.step();
  EXPECT_FALSE(sim.sleeping().asleep());
  EXPECT_EQ(sim.sleeping().sleptSteps(), 0);
}

// A grasp wakes it, and the held towel follows the gripper up.
TEST(Sleeping, AGraspWakesItAndTheTowelFollowsTheGripper) {
  Simulation sim(towelScene());
  Pose above = test::makePose(Vec3(0.0, 0.0, 0.81));
  sim.setGripperPose(0, above);
  stepUntilAsleep(sim);
  ASSERT_TRUE(sim.setGrasp(0, true).success);
  EXPECT_FALSE(sim.sleeping().asleep());
  for (int step = 0; step < 30; ++step) {
    above.position.z() += 0.01;
    sim.setGripperPose(0, above);
    sim.step();
  }
  EXPECT_FALSE(sim.sleeping().asleep());
  double highest = 0.0;
  for (const Vec3& x : sim.particles().position) highest = std::max(highest, x.z());
  EXPECT_GT(highest, 1.05);
}

// A held towel sleeps too; moving the gripper that holds it wakes it.
TEST(Sleeping, AMovingGripperThatHoldsItWakesIt) {
  Simulation sim(towelScene());
  Pose above = test::makePose(Vec3(0.0, 0.0, 0.81));
  sim.setGripperPose(0, above);
  for (int step = 0; step < 5; ++step) sim.step();
  ASSERT_TRUE(sim.setGrasp(0, true).success);
  stepUntilAsleep(sim);
  above.position.x() += 0.05;
  sim.setGripperPose(0, above);
  sim.step();
  EXPECT_FALSE(sim.sleeping().asleep());
  EXPECT_EQ(sim.stats().iterations, 10);
}

// A collider moving far from the towel leaves it asleep; one moving onto it wakes it, and the
// towel then gives way under it.
TEST(Sleeping, ACollidingBallWakesItAFarOneDoesNot) {
  Simulation sim(towelScene());
  stepUntilAsleep(sim);
  sim.setObstaclePose(1, test::makePose(Vec3(3.0, 1.0, 1.0)));  // 3 m away
  sim.step();
  EXPECT_TRUE(sim.sleeping().asleep());
  const Vec3Array rest = sim.particles().position;
  // Down onto the towel's middle: 0.1 m ball from 1.0 m to 0.85 m over a few steps, then below.
  for (double z : {0.95, 0.9, 0.87}) {
    sim.setObstaclePose(1, test::makePose(Vec3(0.0, 0.0, z)));
    sim.step();
  }
  EXPECT_FALSE(sim.sleeping().asleep());
  sim.setObstaclePose(1, test::makePose(Vec3(0.0, 0.0, 0.84)));
  sim.step();
  EXPECT_FALSE(sim.sleeping().asleep());
  EXPECT_NE(sim.particles().position, rest);
}

// A floor is a plane, and its bounds end at it (worldBounds): moved far below the towel it leaves
// the towel asleep; rising into the towel it wakes it and lifts it.
TEST(Sleeping, AFloorMovingFarBelowLeavesItAsleepOneRisingIntoItWakesIt) {
  SceneConfig scene = towelScene();
  scene.obstacles.push_back(test::plane("floor", Vec3::UnitZ(), 0.0));
  Simulation sim(scene);
  stepUntilAsleep(sim);
  sim.setObstaclePose(2, test::makePose(Vec3(0.0, 0.0, 0.3)));  // still 0.5 m below
  sim.step();
  EXPECT_TRUE(sim.sleeping().asleep());
  for (double z : {0.6, 0.79, 0.82, 0.85}) {
    sim.setObstaclePose(2, test::makePose(Vec3(0.0, 0.0, z)));
    sim.step();
  }
  EXPECT_FALSE(sim.sleeping().asleep());
  for (const Vec3& x : sim.particles().position) EXPECT_GE(x.z(), 0.85 + 0.005 - 1e-6);
}

// Parameters from outside wake it: gravity turned sideways makes it slide.
TEST(Sleeping, ChangedSolverParametersWakeIt) {
  Simulation sim(towelScene());
  stepUntilAsleep(sim);
  SolverConfig solver = sim.scene().solver;
  // A tilted world, steeper than the friction cone (mu_s 0.5): the towel slides.
  solver.gravity = Vec3(8.0, 0.0, -9.81);
  sim.setSolverConfig(solver);
  EXPECT_FALSE(sim.sleeping().asleep());
  const Vec3 corner = sim.particles().position[0];
  for (int step = 0; step < 30; ++step) sim.step();
  EXPECT_GT(sim.particles().position[0].x() - corner.x(), 0.01);
}

}  // namespace
}  // namespace pbd_cloth
