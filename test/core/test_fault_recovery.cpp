// Fault recovery (Simulation::setFaultRecovery): a step whose result is not finite, or in which a
// free particle moves faster than solver.max_speed, is undone: free particles back where the step
// started, at rest; time goes on, and the following steps run normally.
#include <gtest/gtest.h>

#include <cmath>

#include "pbd_cloth/sim/metrics.h"
#include "pbd_cloth/sim/simulation.h"
#include "test_scenes.h"

namespace pbd_cloth {
namespace {

// A 12 x 12 cloth pinned at its two top corners, bending and self-collision on, swinging: every
// persistent part of the step (friction states, self-collision sides) is in play.
SceneConfig swingingCloth() {
  SceneConfig scene = test::clothScene(12, 12, 0.04, Method::kXpbd);
  scene.cloth.mass = 0.1;
  scene.cloth.pinned = {0, 11};
  scene.cloth.bend_compliance = 1e-3;
  scene.cloth.self_collision = true;
  scene.solver.substeps = 8;
  return scene;
}

void expectStepUndone(Simulation& sim, InjectedFault injected, StepFault::Kind expected) {
  for (int k = 0; k < 20; ++k) sim.step();
  const Vec3Array before = sim.particles().position;
  const double time_before = sim.time();
  sim.injectFaultForTesting(injected);
  sim.step();

  EXPECT_TRUE(allFinite(sim.particles()));
  EXPECT_TRUE(sim.faultGuard().lastStepRestored());
  EXPECT_EQ(sim.faultGuard().restoredSteps(), 1u);
  EXPECT_EQ(sim.faultGuard().lastFault().kind, expected);
  EXPECT_GE(sim.faultGuard().lastFault().particle, 0);
  EXPECT_NEAR(sim.faultGuard().lastFault().time, sim.time(), 1e-12);
  // Time goes on; every particle is where the step started (the pins never moved), at rest.
  EXPECT_NEAR(sim.time(), time_before + 1.0 / sim.scene().step_rate, 1e-12);
  for (int i = 0; i < sim.particles().size(); ++i) {
    ASSERT_EQ(sim.particles().position[i], before[i]) << "particle " << i;
    ASSERT_EQ(sim.particles().velocity[i], Vec3::Zero()) << "particle " << i;
  }

  // The simulation goes on from there: it swings again, finite, with no further fault.
  for (int k = 0; k < 30; ++k) sim.step();
  EXPECT_TRUE(allFinite(sim.particles()));
  EXPECT_EQ(sim.faultGuard().restoredSteps(), 1u);
  EXPECT_FALSE(sim.faultGuard().lastStepRestored());
  const int corner = sim.particles().size() - 1;  // free, and it swings (the top row is held)
  EXPECT_GT((sim.particles().position[corner] - before[corner]).norm(), 1e-3)
      << "the cloth did not move on after the recovery";
  EXPECT_LT(sim.computeMetrics().max_strain, 0.05);
}

TEST(FaultRecovery, NaNInsideTheStepIsUndone) {
  Simulation sim(swingingCloth());
  sim.setFaultRecovery(true);
  expectStepUndone(sim, InjectedFault::kNaN, StepFault::Kind::kNonFinite);
}

TEST(FaultRecovery, EnergyBlowUpInsideTheStepIsUndone) {
  Simulation sim(swingingCloth());
  sim.setFaultRecovery(true);
  expectStepUndone(sim, InjectedFault::kBlowUp, StepFault::Kind::kTooFast);
  EXPECT_GT(sim.faultGuard().lastFault().speed, sim.scene().solver.max_speed);
}

// Off (the default: benchmarks and stability tests must see a method fail), the fault stays.
TEST(FaultRecovery, OffLeavesTheFailedStepAsItIs) {
  Simulation sim(swingingCloth());
  EXPECT_FALSE(sim.faultGuard().enabled());
  for (int k = 0; k < 5; ++k) sim.step();
  sim.injectFaultForTesting(InjectedFault::kNaN);
  sim.step();
  EXPECT_FALSE(allFinite(sim.particles()));
  EXPECT_EQ(sim.faultGuard().restoredSteps(), 0u);
}

// A real blow-up, no injection: explicit springs far too stiff for one substep (the stability
// limit of symplectic Euler is h < 2 sqrt(m / k): here 0.017 s > 2 sqrt(0.0007 / 1e6) = 5e-5 s).
// Without recovery the cloth diverges; with it, no step's result is ever non-finite or too fast,
// and the cloth stays within its start (each failed step is undone to rest).
TEST(FaultRecovery, UnstableSpringsNeverPublishABlowUp) {
  SceneConfig scene = swingingCloth();
  scene.solver.method = Method::kMassSpring;
  scene.solver.spring_stiffness = 1e6;
  scene.solver.substeps = 1;
  {
    Simulation unguarded(scene);
    bool failed = false;
    for (int k = 0; k < 120 && !failed; ++k) {
      unguarded.step();
      failed = unguarded.findFault().kind != StepFault::Kind::kNone;
    }
    ASSERT_TRUE(failed) << "the setting is meant to blow up";
  }
  Simulation sim(scene);
  sim.setFaultRecovery(true);
  for (int k = 0; k < 120; ++k) {
    sim.step();
    ASSERT_EQ(sim.findFault().kind, StepFault::Kind::kNone) << "step " << k;
  }
  EXPECT_GT(sim.faultGuard().restoredSteps(), 0u);
}

// The message a node logs names the particle and the limit.
TEST(FaultRecovery, DescribeNamesTheParticle) {
  StepFault fault;
  fault.kind = StepFault::Kind::kTooFast;
  fault.particle = 12;
  fault.speed = 1.5e4;
  fault.time = 2.5;
  EXPECT_EQ(describe(fault, 100.0),
            "particle 12 at 15000 m/s (solver.max_speed 100 m/s) at t = 2.5 s");
  fault.kind = StepFault::Kind::kNonFinite;
  EXPECT_EQ(describe(fault, 100.0), "particle 12 not finite at t = 2.5 s");
}

}  // namespace
}  // namespace pbd_cloth
