// Live tuning groups (solver_tuning.h): each group is applied or refused on its own.
#include <gtest/gtest.h>

#include <string>

#include "pbd_cloth/ros/solver_tuning.h"
#include "pbd_cloth/sim/simulation.h"

namespace pbd_cloth {
namespace {

SceneConfig smallScene() {
  SceneConfig scene;
  scene.cloth.rows = 4;
  scene.cloth.cols = 4;
  scene.cloth.self_collision = false;
  return scene;
}

TEST(SolverTuning, RoundTripsTheSimulationsValues) {
  Simulation sim(smallScene());
  SolverTuning tuning = tuningFromSimulation(sim);
  EXPECT_EQ(tuning.substeps, sim.scene().solver.substeps);
  tuning.substeps = 3;
  tuning.ordering = 1;
  tuning.bend_compliance = 0.5;
  std::string errors;
  EXPECT_TRUE(applyTuning(tuning, kTuneSolver | kTuneCompliance | kTuneFriction, sim, errors));
  EXPECT_TRUE(errors.empty());
  EXPECT_EQ(sim.scene().solver.substeps, 3);
  EXPECT_EQ(sim.scene().solver.ordering, Ordering::kJacobi);
  EXPECT_DOUBLE_EQ(sim.scene().cloth.bend_compliance, 0.5);
  sim.step();
  EXPECT_EQ(sim.stats().substeps, 3);
}

TEST(SolverTuning, ARefusedGroupKeepsItsOldValuesAndTheOthersApply) {
  Simulation sim(smallScene());
  const FrictionConfig friction_before = sim.scene().cloth.friction;
  SolverTuning tuning = tuningFromSimulation(sim);
  tuning.substeps = 4;
  tuning.friction_kinetic = tuning.friction_static + 1.0;  // above static: refused
  std::string errors;
  EXPECT_FALSE(applyTuning(tuning, kTuneSolver | kTuneFriction, sim, errors));
  EXPECT_NE(errors.find("cloth.friction.kinetic"), std::string::npos) << errors;
  EXPECT_EQ(sim.scene().solver.substeps, 4);
  EXPECT_DOUBLE_EQ(sim.scene().cloth.friction.kinetic_coefficient,
                   friction_before.kinetic_coefficient);
}

TEST(SolverTuning, OnlyTheNamedGroupsAreTouched) {
  Simulation sim(smallScene());
  SolverTuning tuning = tuningFromSimulation(sim);
  tuning.substeps = 7;
  tuning.damping = 2.0;
  std::string errors;
  EXPECT_TRUE(applyTuning(tuning, kTuneFriction, sim, errors));
  EXPECT_NE(sim.scene().solver.substeps, 7);
}

}  // namespace
}  // namespace pbd_cloth
