// The method features of issue 3 that have no closed-form reference case: PBD stiffness, point
// masses, tethers, kinematic interpolation across substeps, damping, Verlet's start, Jacobi on a
// cloth and determinism. Each test compares with the answer the feature promises.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <vector>

#include "accuracy_helpers.h"
#include "pbd_cloth/sim/simulation.h"

namespace pbd_cloth {
namespace {

using test::kG;
using test::kPi;

// A 10 x 10 cloth, 5 cm spacing, hanging from its two top corners.
SceneConfig hangingCloth(Method method) {
  SceneConfig scene = test::clothScene(10, 10, 0.05, method);
  scene.cloth.rpy = Eigen::Vector3d(kPi / 2.0, 0.0, 0.0);  // grid -y turned into -z: hangs down
  scene.cloth.pinned = {0, 9};
  scene.cloth.mass = 0.2;
  return scene;
}

double maxStrainAfter(const SceneConfig& scene, int steps) {
  Simulation sim(scene);
  double worst = 0.0;
  for (int k = 0; k < steps; ++k) {
    sim.step();
    worst = std::max(worst, sim.stats().max_strain);
  }
  return worst;
}

// PBD stiffness in [0,1] (Mueller et al. 2007): k = 1 projects fully, k = 0.5 leaves part of each
// correction undone, so the cloth stretches more; k = 0 leaves the stretch constraints inactive.
TEST(Methods, PbdStiffnessHalfStretchesMoreThanOne) {
  SceneConfig scene = hangingCloth(Method::kPbd);
  scene.solver.iterations = 10;
  scene.solver.stretch_stiffness = 1.0;
  const double stiff = maxStrainAfter(scene, 60);
  scene.solver.stretch_stiffness = 0.5;
  const double soft = maxStrainAfter(scene, 60);
  scene.solver.stretch_stiffness = 0.0;
  const double none = maxStrainAfter(scene, 60);
  std::printf("pbd max strain over 1 s: k = 1 %.3e, k = 0.5 %.3e, k = 0 %.3e\n", stiff, soft, none);
  EXPECT_GT(soft, 1.5 * stiff);
  EXPECT_GT(none, 10.0 * soft);  // free fall of everything but the pins: huge strain
}

// cloth.point_masses sets the mass (and inverse mass) of single particles; the rest keep
// cloth.mass / count; a pinned particle stays kinematic whatever its mass.
TEST(Methods, PointMassesSetMasses) {
  SceneConfig scene = hangingCloth(Method::kXpbd);
  scene.cloth.point_masses = {{99, 3.0}, {50, 0.25}, {0, 7.0}};
  Simulation sim(scene);
  const Particles& p = sim.particles();
  EXPECT_DOUBLE_EQ(p.mass[99], 3.0);
  EXPECT_DOUBLE_EQ(p.inverse_mass[99], 1.0 / 3.0);
  EXPECT_DOUBLE_EQ(p.mass[50], 0.25);
  EXPECT_DOUBLE_EQ(p.inverse_mass[50], 4.0);
  EXPECT_DOUBLE_EQ(p.mass[0], 7.0);
  EXPECT_EQ(p.inverse_mass[0], 0.0);
  EXPECT_DOUBLE_EQ(p.mass[1], 0.2 / 100);
  EXPECT_DOUBLE_EQ(p.inverse_mass[1], 100 / 0.2);
}

// Long-range attachments (Kim, Chentanez, Mueller 2012): no free particle ever gets further from a
// pinned particle than its rest distance, even when the stretch constraints are far from
// converged (1 pass per step). Two pins at the top corners make the balls of every top-row
// particle touch (the row can only be straight), three or four pins add more anchors per particle.
// Without tethers the same cloth overstretches by a factor of several.
double worstTetherViolation(bool tethers, Method method, const std::vector<int>& pins) {
  SceneConfig scene = hangingCloth(method);
  scene.cloth.pinned = pins;
  scene.cloth.tethers = tethers;
  scene.solver.substeps = 1;
  scene.solver.iterations = 1;
  Simulation sim(scene);
  const Particles& p = sim.particles();
  double worst = -1.0;  // relative excess over the rest distance
  for (int k = 0; k < 120; ++k) {
    sim.step();
    for (int i = 0; i < p.cloth_count; ++i) {
      if (p.isKinematic(i)) continue;
      for (int a : pins) {
        const double dr = i / 10 - a / 10, dc = i % 10 - a % 10;
        const double rest = 0.05 * std::sqrt(dr * dr + dc * dc);
        worst = std::max(worst, (p.position[i] - p.position[a]).norm() / rest - 1.0);
      }
    }
  }
  return worst;
}

TEST(Methods, TethersNeverExceedRestDistanceFromAnchors) {
  for (const std::vector<int>& pins :
       {std::vector<int>{0, 9}, std::vector<int>{0, 4, 9}, std::vector<int>{0, 9, 90}}) {
    for (Method method : {Method::kXpbd, Method::kPbd, Method::kVerlet}) {
      const double with = worstTetherViolation(true, method, pins);
      const double without = worstTetherViolation(false, method, pins);
      std::printf(
          "%s, %zu pins, 1 pass: largest relative excess over the rest distance to a pin: "
          "with tethers %.2e, without %.2e\n",
          toString(method), pins.size(), with, without);
      EXPECT_LE(with, 1e-12) << toString(method) << " " << pins.size() << " pins";
      EXPECT_GT(without, 0.01) << toString(method);  // the test has something to prevent
    }
  }
}

// Anchors joined by stretch links (a pinned edge, the patch one gripper holds) form one group, and
// a particle keeps only its tether to the nearest anchor of each group: one per particle for a
// pinned top edge (the anchor of its column, at its row's distance) where every anchor used to give
// one, two for two separate pins. A gripper holding four particles of a corner adds one more, and a
// second gripper holding the patch beside it one more again.
// The single tether still does the job: with 1 pass per step no particle gets further from the
// anchor of its column than its rest distance, and the edge-hung cloth stretches far less than
// without tethers.
TEST(Methods, TethersKeepTheNearestAnchorOfEachLinkedGroup) {
  SceneConfig scene = hangingCloth(Method::kXpbd);
  scene.cloth.tethers = true;
  scene.cloth.pinned = {0, 1, 2, 3, 4, 5, 6, 7, 8, 9};
  scene.solver.substeps = 1;
  {
    Simulation sim(scene);
    const std::vector<Tether>& tethers = sim.topology().tethers;
    ASSERT_EQ(tethers.size(), 90u);
    for (const Tether& t : tethers) {
      EXPECT_EQ(t.anchor, t.particle % 10) << "particle " << t.particle;
      EXPECT_NEAR(t.max_length, 0.05 * (t.particle / 10), 1e-15) << "particle " << t.particle;
    }
  }
  double worst_excess = 0.0;  // over the rest distance to the anchor of the particle's column
  auto largestStrain = [&](bool tethers) {
    scene.cloth.tethers = tethers;
    Simulation sim(scene);
    const Particles& p = sim.particles();
    double largest = 0.0;
    for (int k = 0; k < 120; ++k) {
      sim.step();
      largest = std::max(largest, sim.stats().max_strain);
      for (int i = 10; tethers && i < 100; ++i) {
        const double rest = 0.05 * (i / 10);
        worst_excess =
            std::max(worst_excess, (p.position[i] - p.position[i % 10]).norm() / rest - 1);
      }
    }
    return largest;
  };
  const double with = largestStrain(true), without = largestStrain(false);
  std::printf(
      "top edge pinned, 1 pass: max strain with tethers %.2e, without %.2e; largest excess "
      "over a column's rest distance %.2e\n",
      with, without, worst_excess);
  EXPECT_LE(worst_excess, 1e-12);
  EXPECT_LT(with, 0.1 * without);

  scene.cloth.tethers = true;
  scene.cloth.pinned = {0, 9};
  EXPECT_EQ(Simulation(scene).topology().tethers.size(), 2u * 98u);  // two groups
  GripperConfig gripper;
  gripper.name = "hand";
  gripper.radius = 0.075;  // particles 90, 91, 80 and 81 (0, 0.05 and 0.071 m from the corner)
  Waypoint hold;
  hold.pose.position = Vec3(0.0, 0.0, -0.45);  // particle 90, the bottom-left corner
  hold.grasp = 1;
  gripper.trajectory = {hold};
  scene.grippers = {gripper};
  Simulation held(scene);
  held.step();
  ASSERT_EQ(held.particles().isKinematic(81), true);
  EXPECT_EQ(held.topology().tethers.size(), 3u * 94u);  // the pins' two groups and the gripper's

  // A second gripper holding the patch beside the first (82-84 and 92-94, linked to 81 and 91): a
  // group of its own, since the two grippers may move apart.
  GripperConfig second = gripper;
  second.name = "other";
  second.trajectory.front().pose.position = Vec3(0.15, 0.0, -0.45);  // particle 93
  scene.grippers = {gripper, second};
  Simulation both(scene);
  both.step();
  ASSERT_TRUE(both.particles().isKinematic(82) && both.particles().isKinematic(94));
  EXPECT_EQ(both.topology().tethers.size(), 4u * 88u);
}

// Kinematic particles move along the straight line from where they are to their target across the
// substeps of a step (not in one jump at the first substep), and sit exactly on the gripper at the
// end of every step. A gripper grasps particles 0 and 1, moves them 0.3 m along x and 0.2 m up in
// 1 s while turning 90 deg about z, then releases them at t = 1.5 s.
TEST(Methods, GraspedParticlesFollowGripperSmoothlyAcrossSubsteps) {
  SceneConfig scene = hangingCloth(Method::kXpbd);
  scene.cloth.pinned.clear();
  scene.solver.substeps = 8;
  const int substeps = scene.solver.substeps;
  GripperConfig gripper;
  gripper.name = "left";
  gripper.radius = 0.03;
  Waypoint start, end, release;
  start.t = 0.0;
  start.pose.position = Vec3(0.025, 0.0, 0.0);  // between particles 0 and 1, 2.5 cm from each
  start.grasp = 1;
  end.t = 1.0;
  end.pose.position = Vec3(0.325, 0.0, 0.2);
  end.pose.orientation = Eigen::Quaterniond(Eigen::AngleAxisd(kPi / 2.0, Vec3::UnitZ()));
  release = end;
  release.t = 1.5;
  release.grasp = 0;
  gripper.trajectory = {start, end, release};
  scene.grippers = {gripper};
  Simulation sim(scene);
  const Particles& p = sim.particles();
  const double dt = 1.0 / scene.step_rate, h = dt / substeps;
  const Vec3 offset0 = p.position[0] - start.pose.position;
  const Vec3 offset1 = p.position[1] - start.pose.position;

  double worst_follow = 0.0, worst_substep = 0.0;
  for (int k = 0; k < 80; ++k) {
    const Vec3 before = p.position[0];
    sim.step();
    ASSERT_TRUE(sim.grippers().grasping(0));
    ASSERT_TRUE(p.isKinematic(0) && p.isKinematic(1));
    const double t = std::min(1.0, sim.time());
    const Eigen::Quaterniond q = start.pose.orientation.slerp(t, end.pose.orientation);
    const Vec3 centre = (1.0 - t) * start.pose.position + t * end.pose.position;
    worst_follow = std::max(worst_follow, (p.position[0] - (centre + q * offset0)).norm());
    worst_follow = std::max(worst_follow, (p.position[1] - (centre + q * offset1)).norm());
    // The last substep started 7/8 of the way and moved 1/8 of the step's displacement: the
    // substep path is the chord of the step, travelled at constant speed.
    const Vec3 step_displacement = p.position[0] - before;
    worst_substep = std::max(
        worst_substep,
        (p.substep_start[0] - (before + (substeps - 1.0) / substeps * step_displacement)).norm());
    worst_substep =
        std::max(worst_substep, (h * p.velocity[0] - step_displacement / substeps).norm());
  }
  std::printf(
      "grasped particles: largest distance from the gripper at step ends %.2e m, largest "
      "departure from uniform substep motion %.2e m\n",
      worst_follow, worst_substep);
  EXPECT_LT(worst_follow, 1e-9);
  EXPECT_LT(worst_substep, 1e-12);

  // Held after the last waypoint; released at 1.5 s with the gripper's (zero) velocity.
  while (sim.time() < 1.5 + 0.5 * dt) sim.step();
  EXPECT_FALSE(sim.grippers().grasping(0));
  EXPECT_FALSE(p.isKinematic(0));
  for (int k = 0; k < 10; ++k) sim.step();
  EXPECT_LT(p.position[0].z(), end.pose.position.z() - 0.01);  // free again: it falls
}

// A released particle keeps its own velocity in the gripper, the turning included: v + omega x r.
// A rope of 4 particles 5 cm apart, all held by a gripper at the first one that moves at
// v = (0.1, 0, 0.2) m/s while it turns about z at 2 rad/s, is let go after 1 s. Each particle's
// velocity is the chord of its path over the last step, which lags the tangent omega x r by half
// the step's turn: tolerance 0.6 |omega|^2 r dt (0.5 to first order). The gripper's linear velocity
// alone, as before, misses the far particle by |omega| r = 0.3 m/s.
TEST(Methods, ReleasedParticlesKeepTheirVelocityIncludingTheGrippersRotation) {
  const Vec3 v(0.1, 0.0, 0.2);
  const double omega = 2.0, dt = 1.0 / 60.0;
  for (Method method : {Method::kXpbd, Method::kPbd, Method::kVerlet, Method::kMassSpring}) {
    SceneConfig scene = test::clothScene(1, 4, 0.05, method);
    scene.solver.gravity.setZero();
    scene.solver.substeps = 4;
    GripperConfig gripper;
    gripper.name = "hand";
    gripper.radius = 0.16;
    Waypoint start, end;
    start.t = 0.0;
    start.grasp = 1;
    end.t = 1.0;
    end.pose.position = v;
    end.pose.orientation = Eigen::Quaterniond(Eigen::AngleAxisd(omega, Vec3::UnitZ()));
    gripper.trajectory = {start, end};
    scene.grippers = {gripper};
    Simulation sim(scene);
    while (sim.time() < 1.0 - 0.5 * dt) sim.step();
    ASSERT_TRUE(sim.grippers().grasping(0)) << toString(method);
    ASSERT_EQ(sim.setGrasp(0, false).grasped_count, 4) << toString(method);

    const Particles& p = sim.particles();
    const Vec3 centre = sim.grippers().pose(0).position;
    const Vec3 spin = omega * Vec3::UnitZ();
    for (int i = 0; i < 4; ++i) {
      const Vec3 r = p.position[i] - centre;
      const Vec3 expected = v + spin.cross(r);
      const double tolerance = 0.6 * omega * omega * r.norm() * dt + 1e-9;
      EXPECT_NEAR((p.velocity[i] - expected).norm(), 0.0, tolerance)
          << toString(method) << " particle " << i << " at r = " << r.norm() << " m: velocity "
          << p.velocity[i].transpose() << ", v + omega x r = " << expected.transpose();
    }
    EXPECT_GT((p.velocity[3] - v).norm(), 0.25) << toString(method) << ": the turn is left out";
  }
}

// Damping dv/dt = -c v: a free particle's speed decays as e^{-c t} whatever the substep count
// (the factor e^{-c h} per substep composes exactly), and gravity is not damped at rest.
TEST(Methods, DampingDecaysVelocityExponentiallyForAnySubstepCount) {
  for (int substeps : {1, 7, 50}) {
    SceneConfig scene = test::clothScene(1, 2, 0.1, Method::kXpbd);
    scene.solver.gravity.setZero();
    scene.solver.damping = 2.0;
    scene.solver.substeps = substeps;
    Simulation sim(scene);
    for (auto& v : sim.mutableParticles().velocity) v = Vec3(1.0, 0.0, 0.0);
    for (int k = 0; k < 60; ++k) sim.step();
    EXPECT_NEAR(sim.particles().velocity[0].x(), std::exp(-2.0), 1e-12) << substeps;
    // Travelled distance: sum of h e^{-c h j}, j = 1..n, the exact discrete sum.
    const double h = 1.0 / (60.0 * substeps), r = std::exp(-2.0 * h);
    const double travelled = h * r * (1.0 - std::pow(r, 60 * substeps)) / (1.0 - r);
    EXPECT_NEAR(sim.particles().position[0].x(), travelled, 1e-12) << substeps;
  }
}

// Verlet's start x_prev = x0 - v0 h + g h^2 / 2 (REFERENCE_CASES.md case 1) makes a throw exact
// too: x(t) = x0 + v0 t + g t^2 / 2 at every step, for any substep count.
TEST(Methods, VerletThrowIsExact) {
  for (int substeps : {1, 4}) {
    SceneConfig scene = test::clothScene(1, 2, 0.1, Method::kVerlet);
    scene.solver.substeps = substeps;
    Simulation sim(scene);
    const Vec3 v0(2.0, 0.5, 5.0), x0 = sim.particles().position[0];
    // The stored Verlet velocity is the half-step one, v0 - g h / 2: add the throw to it.
    for (auto& v : sim.mutableParticles().velocity) v += v0;
    for (int k = 1; k <= 60; ++k) {
      sim.step();
      const double t = k / 60.0;
      const Vec3 exact = x0 + v0 * t + 0.5 * t * t * scene.solver.gravity;
      ASSERT_LT((sim.particles().position[0] - exact).norm(), 1e-11) << substeps << " " << k;
    }
  }
}

// Jacobi on a real cloth: summed (plain) corrections overshoot wherever a particle has more than
// two constraints and the cloth blows up; averaged ones converge, if slowly (Jacobi needs several
// times the passes of Gauss-Seidel): the strain left after a step falls as passes are added.
double jacobiStrain(bool averaging, int passes) {
  SceneConfig scene = hangingCloth(Method::kXpbd);
  scene.solver.ordering = Ordering::kJacobi;
  scene.solver.iterations = passes;
  scene.solver.jacobi_averaging = averaging;
  Simulation sim(scene);
  for (int k = 0; k < 60; ++k) sim.step();
  const Metrics metrics = sim.computeMetrics();
  return metrics.finite ? metrics.max_strain : std::numeric_limits<double>::infinity();
}

TEST(Methods, JacobiOnClothNeedsAveraging) {
  const double few = jacobiStrain(true, 5), some = jacobiStrain(true, 20);
  const double many = jacobiStrain(true, 100), plain = jacobiStrain(false, 20);
  std::printf(
      "jacobi max strain after 1 s: averaged 5 passes %.3e, 20 passes %.3e, 100 passes "
      "%.3e; plain 20 passes %.3e\n",
      few, some, many, plain);
  EXPECT_LT(some, few);
  EXPECT_LT(many, 0.5 * some);
  EXPECT_LT(many, 0.3);
  EXPECT_GT(plain, 1e3);  // diverged (infinite: positions no longer finite)
}

// Determinism: the same scene and inputs give bit-identical states (no threads, no unordered
// containers, no time-dependent branches in the step). Grippers, tethers, bending and both
// orderings.
TEST(Methods, SameSceneGivesBitIdenticalStates) {
  for (Ordering ordering : {Ordering::kGaussSeidel, Ordering::kJacobi}) {
    SceneConfig scene = hangingCloth(Method::kXpbd);
    scene.solver.ordering = ordering;
    scene.solver.substeps = 4;
    scene.solver.iterations = 2;
    scene.cloth.bend_compliance = 1e-3;
    scene.cloth.tethers = true;
    scene.cloth.self_collision = true;
    GripperConfig gripper;
    gripper.name = "g";
    gripper.radius = 0.03;
    Waypoint a, b;
    a.pose.position = Vec3(0.225, 0.0, -0.45);  // near the middle of the bottom row
    a.grasp = 1;
    b.t = 0.5;
    b.pose.position = Vec3(0.3, 0.2, -0.2);
    b.grasp = 0;
    gripper.trajectory = {a, b};
    scene.grippers = {gripper};
    Simulation one(scene), two(scene);
    for (int k = 0; k < 90; ++k) {
      one.step();
      two.step();
      ASSERT_TRUE(one.particles().position == two.particles().position) << k;
      ASSERT_TRUE(one.particles().velocity == two.particles().velocity) << k;
    }
    // And after a reset, the same run again.
    const Vec3Array final_positions = one.particles().position;
    one.reset();
    for (int k = 0; k < 90; ++k) one.step();
    EXPECT_TRUE(one.particles().position == final_positions) << toString(ordering);
  }
}

}  // namespace
}  // namespace pbd_cloth
