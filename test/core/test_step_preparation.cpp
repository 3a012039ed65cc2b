// The solver keeps a step's preparations (the links' and hinges' per-step terms, the kinematic
// lists: Solver::step) while h and the inverse masses stand, and makes them again when either
// changes: a grasp, a release, a new step length. A run that is made to prepare at every step
// (a compliance set to the value it has, which invalidates them) must end in the same place.
#include <gtest/gtest.h>

#include "collision_scenes.h"
#include "pbd_cloth/sim/simulation.h"
#include "pbd_cloth/state/saved_state.h"
#include "test_scenes.h"

namespace pbd_cloth {
namespace {

SceneConfig graspScene() {
  SceneConfig scene = test::clothScene(12, 12, 0.05, Method::kXpbd);
  scene.cloth.bend_compliance = 1e-3;
  scene.cloth.self_collision = false;
  scene.cloth.pinned = {0};
  GripperConfig gripper;
  gripper.name = "hand";
  gripper.radius = 0.06;
  scene.grippers = {gripper};
  return scene;
}

TEST(StepPreparation, KeptOnlyWhileTheKinematicSetAndStepStand) {
  const SceneConfig scene = graspScene();
  Simulation kept(scene), fresh(scene);
  const Vec3 corner = kept.particles().position[11];
  auto stepBoth = [&](int steps, double dt) {
    for (int k = 0; k < steps; ++k) {
      // Same compliances: nothing changes but the solver's preparations, made again.
      fresh.setClothCompliance(scene.cloth.stretch_compliance, scene.cloth.bend_compliance);
      kept.step(dt);
      fresh.step(dt);
    }
  };
  const double dt = 1.0 / scene.step_rate;
  stepBoth(5, dt);
  // The gripper on the free corner of row 0 (particle 11), where it has fallen to.
  Pose hand;
  hand.position = kept.particles().position[11];
  ASSERT_TRUE(kept.setGripperPose(0, hand));
  ASSERT_TRUE(fresh.setGripperPose(0, hand));
  stepBoth(1, dt);  // the gripper moves there
  const GraspResult grasp = kept.setGrasp(0, true);
  ASSERT_GT(grasp.grasped_count, 0) << "the gripper holds no particle: the test tests nothing";
  ASSERT_EQ(fresh.setGrasp(0, true).grasped_count, grasp.grasped_count);
  const Vec3 held = kept.particles().position[11];
  stepBoth(20, dt);
  EXPECT_LT((kept.particles().position[11] - held).norm(), 1e-9) << "the grasp did not hold";
  kept.setGrasp(0, false);
  fresh.setGrasp(0, false);
  stepBoth(20, dt);
  stepBoth(10, 0.5 * dt);  // a new h
  EXPECT_EQ(kept.particles().position, fresh.particles().position);
  EXPECT_EQ(kept.particles().velocity, fresh.particles().velocity);
  EXPECT_GT((kept.particles().position[11] - corner).norm(), 0.1) << "released, it falls";
}

// The step leaves out what only a report needs: Simulation::stats() measures the strain and the
// penetration of the state when asked, once per state. Whatever changed the state since (a step,
// direct access to the particles, a restored state, a reset), they describe the state as it is,
// the same figures as computeMetrics().
TEST(StepPreparation, StatsMeasureTheStateAsItIsWhenAsked) {
  SceneConfig scene = test::clothScene(8, 8, 0.02, Method::kXpbd);
  scene.cloth.pinned = {0, 7};
  // A block 1 m below the pinned cloth: nothing touches it unless put there.
  scene.obstacles = {test::box("block", Vec3(2.0, 2.0, 0.2), test::makePose(Vec3(0, 0, -1.1)))};
  Simulation sim(scene);
  auto expectMeasured = [&](const char* when) {
    const Metrics metrics = sim.computeMetrics();
    EXPECT_EQ(sim.stats().max_strain, metrics.max_strain) << when;
    EXPECT_EQ(sim.stats().mean_strain, metrics.mean_strain) << when;
    EXPECT_EQ(sim.stats().max_penetration, metrics.max_penetration) << when;
  };
  expectMeasured("built");
  for (int k = 0; k < 20; ++k) sim.step();
  expectMeasured("after 20 steps");
  const double swinging = sim.stats().max_strain;
  SimulationState saved;
  sim.getState(saved);
  // Particle 9 (row 1) pulled 1 cm sideways stretches its links; particle 63 put 5 cm deep into
  // the block.
  sim.mutableParticles().position[9].x() += 0.01;
  sim.mutableParticles().position[63] = Vec3(0.0, 0.0, -1.05);
  expectMeasured("particles moved");
  EXPECT_GT(sim.stats().max_strain, swinging + 0.1);
  EXPECT_GT(sim.stats().max_penetration, 0.04);
  std::string reason;
  ASSERT_TRUE(sim.setState(saved, reason)) << reason;
  expectMeasured("state restored");
  EXPECT_EQ(sim.stats().max_strain, swinging);
  EXPECT_EQ(sim.stats().max_penetration, 0.0);
  sim.mutableParticles().position[9].x() += 0.01;
  sim.reset();
  expectMeasured("reset");
  EXPECT_EQ(sim.stats().max_strain, 0.0);  // the grid as built
}

}  // namespace
}  // namespace pbd_cloth
