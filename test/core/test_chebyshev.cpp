// solver.chebyshev: the Chebyshev semi-iterative method over a substep's passes (Wang 2015;
// Solver::accelerate).
#include <gtest/gtest.h>

#include <cstdio>

#include "pbd_cloth/sim/simulation.h"
#include "test_scenes.h"

namespace pbd_cloth {
namespace {

constexpr double kPi = 3.14159265358979323846;

// A 32 x 32 inextensible cloth, 0.93 m, pinned at the two corners of its first row, that starts
// flat and swings down (issue 12's swinging cloth, smaller): a Gauss-Seidel pass leaves a stretch
// that more passes remove slowly, the error Chebyshev's extrapolation is for. Its largest part
// is along the taut first row, which solver.taut_chains would hold straight instead: off here, so
// that the passes carry that error as they did when these figures were measured.
SceneConfig swingingCloth(int substeps, int iterations, double chebyshev) {
  SceneConfig scene = test::clothScene(32, 32, 0.03, Method::kXpbd);
  scene.cloth.pinned = {0, 31};
  scene.solver.taut_chains = false;
  scene.cloth.mass = 0.2;
  scene.solver.substeps = substeps;
  scene.solver.iterations = iterations;
  scene.solver.chebyshev = chebyshev;
  return scene;
}

Vec3Array positionsAfter(const SceneConfig& scene, int steps) {
  Simulation sim(scene);
  for (int k = 0; k < steps; ++k) sim.step();
  return sim.particles().position;
}

// Largest strain of the links after 0.5 s, in the middle of the cloth's first swing.
double strainAfterSwing(const SceneConfig& scene) {
  Simulation sim(scene);
  for (int k = 0; k < 30; ++k) sim.step();
  return sim.stats().max_strain;
}

// Reference: an inextensible cloth has zero strain. With the same passes (10 substeps of 4, then
// of 8) the extrapolation leaves less stretch than plain Gauss-Seidel: measured 0.48x and 0.29x
// (2026-11-27); asserted with room, 0.6x and 0.4x. Its gain grows with the passes,
// as the Chebyshev polynomials' damping does.
TEST(Chebyshev, LeavesLessStretchThanTheSamePassesWithout) {
  const double plain = strainAfterSwing(swingingCloth(10, 4, 0.0));
  const double accelerated = strainAfterSwing(swingingCloth(10, 4, 0.9));
  const double plain_more = strainAfterSwing(swingingCloth(10, 8, 0.0));
  const double accelerated_more = strainAfterSwing(swingingCloth(10, 8, 0.9));
  std::printf(
      "max strain at 0.5 s: 10 x 4 plain %.4f, rho 0.9 %.4f; 10 x 8 plain %.4f, rho 0.9 %.4f\n",
      plain, accelerated, plain_more, accelerated_more);
  EXPECT_LT(accelerated, 0.6 * plain);
  EXPECT_LT(accelerated_more, 0.4 * plain_more);
}

// The first pass has no earlier one to extrapolate from and the last one is never extrapolated
// (the substep ends with projected contacts), so with two passes the option changes nothing.
TEST(Chebyshev, TwoPassesAreNeverExtrapolated) {
  EXPECT_TRUE(positionsAfter(swingingCloth(2, 2, 0.0), 10) ==
              positionsAfter(swingingCloth(2, 2, 0.9), 10));
  EXPECT_FALSE(positionsAfter(swingingCloth(2, 3, 0.0), 10) ==
               positionsAfter(swingingCloth(2, 3, 0.9), 10));
}

// Pinned particles keep their place (the extrapolation skips kinematic particles), and the result
// is bit-identical for one and two threads (each particle's extrapolation reads only its own
// positions).
TEST(Chebyshev, KeepsPinsAndIsTheSameOnTwoThreads) {
  SceneConfig scene = swingingCloth(2, 6, 0.9);
  scene.cloth.bend_compliance = 1.0;
  scene.cloth.rpy = Eigen::Vector3d(0.1 * kPi, 0.0, 0.0);
  Simulation one(scene);
  scene.solver.threads = 2;
  Simulation two(scene);
  const Vec3 pin0 = one.particles().position[0], pin31 = one.particles().position[31];
  for (int k = 0; k < 30; ++k) {
    one.step();
    two.step();
  }
  EXPECT_EQ(one.particles().position[0], pin0);
  EXPECT_EQ(one.particles().position[31], pin31);
  EXPECT_TRUE(one.particles().position == two.particles().position);
  EXPECT_TRUE(one.particles().velocity == two.particles().velocity);
}

// The option switched on, and off again, in a running scene (Simulation::setSolverConfig, as the
// node's reconfigure does) gives the same bits as a scene built with that setting: the two
// buffers of the extrapolation are sized on the switch, not only when the scene is built.
TEST(Chebyshev, SwitchedAtRunTimeIsTheSameAsBuiltWithIt) {
  const SceneConfig plain = swingingCloth(2, 6, 0.0);
  const SceneConfig accelerated = swingingCloth(2, 6, 0.9);
  Simulation switched(plain);
  Simulation built(accelerated);
  switched.setSolverConfig(accelerated.solver);
  for (int k = 0; k < 10; ++k) {
    switched.step();
    built.step();
  }
  EXPECT_TRUE(switched.particles().position == built.particles().position);
  Simulation switched_back(plain);
  switched_back.setSolverConfig(accelerated.solver);
  switched_back.setSolverConfig(plain.solver);
  Simulation never(plain);
  for (int k = 0; k < 10; ++k) {
    switched_back.step();
    never.step();
  }
  EXPECT_TRUE(switched_back.particles().position == never.particles().position);
}

}  // namespace
}  // namespace pbd_cloth
