// solver.taut_chains (taut_chains.h): a grid row between two kinematic particles exactly its
// rest length apart is held on the straight segment between them, the one shape its inextensible
// links allow; slack or soft, it is left to the solver; pulled too far, it is held evenly
// stretched; and the grippers holding its ends carry what rests on it.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <vector>

#include "collision_scenes.h"
#include "pbd_cloth/sim/simulation.h"

namespace pbd_cloth {
namespace {

constexpr int kSide = 12;
constexpr double kSpacing = 0.05;

// A 12 x 12 cloth lying flat (the grid's x-y plane, z = 0) that swings down from its two pinned
// top corners, particles 0 and 11: config/swinging.yaml in small.
SceneConfig swingingCloth(bool taut_chains) {
  SceneConfig scene = test::clothScene(kSide, kSide, kSpacing, Method::kXpbd);
  scene.cloth.mass = 0.1;
  scene.cloth.pinned = {0, kSide - 1};
  scene.solver.substeps = 10;
  scene.solver.taut_chains = taut_chains;
  return scene;
}

// The largest distance of a top-row particle from the row's straight line (the x axis).
double topRowSag(const Simulation& sim) {
  double sag = 0.0;
  for (int c = 0; c < kSide; ++c) {
    const Vec3& x = sim.particles().position[c];
    sag = std::max(sag, std::hypot(x.y(), x.z()));
  }
  return sag;
}

double linkLength(const Simulation& sim, int i, int j) {
  return (sim.particles().position[i] - sim.particles().position[j]).norm();
}

// The pinned corners are 11 rest lengths apart along the top row: the row stays exactly on the
// segment between them, each particle at its rest distance (to rounding), while the cloth below
// swings down. Without the option the same row sags under the cloth's weight, which is what the
// option removes.
TEST(TautChains, HoldsATautRowOnItsLine) {
  Simulation held(swingingCloth(true));
  Simulation swept(swingingCloth(false));
  for (int k = 0; k < 60; ++k) {
    held.step();
    swept.step();
    ASSERT_EQ(static_cast<int>(held.tautChains().held().size()), kSide - 2) << "step " << k;
  }
  // Between steps the held particles are free again: a gripper may grasp them.
  for (int c = 1; c < kSide - 1; ++c) EXPECT_FALSE(held.particles().isKinematic(c)) << c;
  EXPECT_LT(held.particles().position[kSide * kSide - 1].z(), -0.3);  // the cloth swung down
  EXPECT_LT(topRowSag(held), 1e-15);
  for (int c = 0; c + 1 < kSide; ++c) {
    EXPECT_NEAR(linkLength(held, c, c + 1), kSpacing, 1e-15) << "link " << c;
  }
  std::printf("top row sag: held %.3g m, swept %.3g m\n", topRowSag(held), topRowSag(swept));
  EXPECT_GT(topRowSag(swept), 1e-4);
  EXPECT_TRUE(swept.tautChains().held().empty());
}

// Two grippers, one at each top corner, grasp it at t = 0, hold still until `still_until` and then
// move by `outward` each (negative: towards each other) until `moved_at`; the pins are left out.
void holdCornersThenMove(SceneConfig& scene, double still_until, double moved_at, double outward) {
  scene.cloth.pinned.clear();
  for (int g = 0; g < 2; ++g) {
    GripperConfig gripper;
    gripper.name = g == 0 ? "left" : "right";
    gripper.radius = 0.01;
    const double x = g == 0 ? 0.0 : (kSide - 1) * kSpacing;
    const double away = g == 0 ? -outward : outward;
    Waypoint hold, still, moved;
    hold.pose = test::makePose(Vec3(x, 0.0, 0.0));
    hold.grasp = 1;
    still.t = still_until;
    still.pose = hold.pose;
    moved.t = moved_at;
    moved.pose = test::makePose(Vec3(x + away, 0.0, 0.0));
    gripper.trajectory = {hold};
    if (still_until > 0.0) gripper.trajectory.push_back(still);
    gripper.trajectory.push_back(moved);
    scene.grippers.push_back(gripper);
  }
}

// Two grippers hold the top corners and then move 5 cm towards each other: while they are the
// row's length apart the row is held; once closer it is slack and free, and sags.
TEST(TautChains, ASlackRowIsFree) {
  SceneConfig scene = swingingCloth(true);
  holdCornersThenMove(scene, 0.5, 1.0, -0.025);
  Simulation sim(scene);
  int held_steps = 0, free_steps = 0;
  for (int k = 0; k < 90; ++k) {
    sim.step();
    const bool held = !sim.tautChains().held().empty();
    if (k < 30) held_steps += held;
    if (k >= 31) free_steps += !held;
  }
  EXPECT_EQ(held_steps, 30);
  EXPECT_EQ(free_steps, 59);
  EXPECT_GT(topRowSag(sim), 1e-3);
}

// Grippers pulling the corners 1 % farther apart than the row's rest length: no shape meets every
// link, and the row is held straight with every link stretched alike (the least-squares answer),
// where the sweep would pile the stretch up near the ends.
TEST(TautChains, PulledApartTheRowStretchesEvenly) {
  SceneConfig scene = swingingCloth(true);
  holdCornersThenMove(scene, 0.0, 0.5, 0.005 * (kSide - 1) * kSpacing);
  Simulation sim(scene);
  for (int k = 0; k < 45; ++k) sim.step();
  ASSERT_EQ(static_cast<int>(sim.tautChains().held().size()), kSide - 2);
  for (int c = 0; c + 1 < kSide; ++c) {
    EXPECT_NEAR(linkLength(sim, c, c + 1) / kSpacing - 1.0, 0.01, 1e-12) << "link " << c;
  }
}

// Turned off live after holding the row, then a gripper grasps a particle the row held: the grasp
// stands after the step (nothing releases what the option no longer holds), and it is grasped
// between steps too, when the held row is free (it was kinematic only inside a step).
TEST(TautChains, TurnedOffLiveLeavesAGraspAlone) {
  SceneConfig scene = swingingCloth(true);
  GripperConfig gripper;
  gripper.name = "hand";
  gripper.radius = 0.01;
  Waypoint above;  // over particle 5 of the top row, holding nothing
  above.pose = test::makePose(Vec3(5 * kSpacing, 0.0, 0.0));
  gripper.trajectory = {above};
  scene.grippers = {gripper};
  Simulation sim(scene);
  for (int k = 0; k < 10; ++k) sim.step();
  ASSERT_EQ(static_cast<int>(sim.tautChains().held().size()), kSide - 2);
  SolverConfig solver = sim.scene().solver;
  solver.taut_chains = false;
  sim.setSolverConfig(solver);
  ASSERT_EQ(sim.setGrasp(0, true).grasped_count, 1);
  sim.step();
  EXPECT_TRUE(sim.tautChains().held().empty());
  EXPECT_TRUE(sim.particles().isKinematic(5));
  EXPECT_TRUE(sim.grippers().grasping(0));
}

// Links that can stretch have more than one shape between the same ends: a compliant cloth, pbd
// with a stretch stiffness under 1 and the explicit springs are never held; nor is a tethered
// cloth's row, which its tethers hold already.
TEST(TautChains, OnlyInextensibleLinksAreHeld) {
  SceneConfig compliant = swingingCloth(true);
  compliant.cloth.stretch_compliance = 1e-6;
  SceneConfig soft_pbd = swingingCloth(true);
  soft_pbd.solver.method = Method::kPbd;
  soft_pbd.solver.stretch_stiffness = 0.9;
  SceneConfig springs = swingingCloth(true);
  springs.solver.method = Method::kMassSpring;
  springs.solver.substeps = 40;
  SceneConfig tethered = swingingCloth(true);  // the tethers hold the row already
  tethered.cloth.tethers = true;
  SceneConfig rigid_pbd = swingingCloth(true);
  rigid_pbd.solver.method = Method::kPbd;
  SceneConfig verlet = swingingCloth(true);
  verlet.solver.method = Method::kVerlet;
  for (const SceneConfig* scene : {&compliant, &soft_pbd, &springs, &tethered}) {
    Simulation sim(*scene);
    for (int k = 0; k < 10; ++k) sim.step();
    EXPECT_TRUE(sim.tautChains().held().empty()) << toString(scene->solver.method);
  }
  for (const SceneConfig* scene : {&rigid_pbd, &verlet}) {
    Simulation sim(*scene);
    for (int k = 0; k < 10; ++k) sim.step();
    EXPECT_EQ(static_cast<int>(sim.tautChains().held().size()), kSide - 2)
        << toString(scene->solver.method);
    EXPECT_LT(topRowSag(sim), 1e-15) << toString(scene->solver.method);
  }
}

// A 10 x 10 cloth of 0.1 kg hanging at rest from two grippers at its top corners, whose row is
// held: the two grippers together carry its whole weight within 2 %. Most of it reaches them
// through the held row (the cloth hangs from the row's particles), which each gripper carries by
// the lever rule; counting only the grippers' own particles would miss nearly all of it.
TEST(TautChains, GrippersCarryWhatHangsFromTheRow) {
  SceneConfig scene = test::clothScene(10, 10, 0.05, Method::kXpbd);
  scene.cloth.mass = 0.1;
  scene.cloth.origin = Vec3(0.0, 0.0, 1.0);
  scene.cloth.rpy = Vec3(test::kPiValue / 2.0, 0.0, 0.0);  // hanging in the x-z plane
  scene.solver.substeps = 8;
  scene.solver.iterations = 4;
  scene.solver.damping = 2.0;
  for (int g = 0; g < 2; ++g) {
    GripperConfig gripper;
    gripper.name = g == 0 ? "left" : "right";
    gripper.radius = 0.01;
    Waypoint start;
    start.t = 0.0;
    start.pose = test::makePose(Vec3(g == 0 ? 0.0 : 0.45, 0.0, 1.0));
    start.grasp = 1;
    gripper.trajectory = {start};
    scene.grippers.push_back(gripper);
  }
  Simulation sim(scene);
  for (int k = 0; k < 600; ++k) sim.step();
  ASSERT_EQ(static_cast<int>(sim.tautChains().held().size()), 8);
  Vec3 force = Vec3::Zero();
  const int steps = 30;
  for (int k = 0; k < steps; ++k) {
    sim.step();
    force += (sim.gripperForce(0) + sim.gripperForce(1)) / steps;
  }
  double mass = 0.0;
  for (double m : sim.particles().mass) mass += m;
  const double weight = mass * test::kGravity;
  std::printf("both grippers: %.5f N, weight %.5f N\n", force.norm(), weight);
  EXPECT_NEAR(force.norm(), weight, 0.02 * weight);
  EXPECT_GT(-force.normalized().z(), std::cos(test::toRadians(1.0)));
}

}  // namespace
}  // namespace pbd_cloth
