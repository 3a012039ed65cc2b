// solver.levels: the hierarchy of long-range links (coarse_levels.h) on grid cloths.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

#include "pbd_cloth/constraints/coarse_levels.h"
#include "pbd_cloth/scene/scene_yaml.h"
#include "pbd_cloth/sim/cloth_builder.h"
#include "pbd_cloth/sim/metrics.h"
#include "pbd_cloth/sim/simulation.h"
#include "test_scenes.h"

namespace pbd_cloth {
namespace {

constexpr double kSpacing = 0.1;

// A flat 9 x 9 grid (in the x-y plane) scaled by `factor` about particle 0, which is pinned.
Particles scaledGrid(double factor) {
  SceneConfig scene = test::clothScene(9, 9, kSpacing, Method::kXpbd);
  scene.cloth.pinned = {0};
  Particles particles;
  ClothTopology topology;
  buildScene(scene, particles, topology);
  for (auto& x : particles.position) x *= factor;
  return particles;
}

double distance(const Particles& p, int i, int j) { return (p.position[i] - p.position[j]).norm(); }

// The levels of a 9 x 9 grid: lines 0 2 4 6 8, then 0 4 8, then 0 8; no fourth.
TEST(CoarseLevels, CoarsensToTheFirstAndLastLines) {
  CoarseLevels levels;
  levels.build(9, 9, kSpacing, 10);
  EXPECT_EQ(levels.levelCount(), 3);
  levels.build(50, 50, kSpacing, 4);
  EXPECT_EQ(levels.levelCount(), 4);
  levels.build(9, 9, kSpacing, 0);
  EXPECT_EQ(levels.levelCount(), 0);
  levels.build(1, 50, kSpacing, 10);  // a rope: coarsened along its length only
  EXPECT_GE(levels.levelCount(), 4);
}

// Unilateral: a cloth shrunk to half its size (every link compressed) is left exactly as it is.
TEST(CoarseLevels, NeverPushParticlesApart) {
  Particles particles = scaledGrid(0.5);
  const Vec3Array before = particles.position;
  CoarseLevels levels;
  levels.build(9, 9, kSpacing, 3);
  levels.prepareStep(particles);
  EXPECT_EQ(levels.project(particles), 0.0);
  EXPECT_EQ(particles.position, before);
}

// A rope stretched by 10 %, pinned at one end: one sweep puts its far end back at its rest
// distance (every link is on a line, so contracting a link only moves its ends inward): the stretch
// of all its links removed at once, which one Gauss-Seidel pass over the rope's own links cannot.
TEST(CoarseLevels, OneSweepRemovesTheStretchOfAWholeRope) {
  SceneConfig scene = test::clothScene(1, 9, kSpacing, Method::kXpbd);
  scene.cloth.pinned = {0};
  Particles particles;
  ClothTopology topology;
  buildScene(scene, particles, topology);
  for (auto& x : particles.position) x *= 1.1;
  CoarseLevels levels;
  levels.build(1, 9, kSpacing, 3);
  ASSERT_EQ(levels.levelCount(), 3);
  levels.prepareStep(particles);
  EXPECT_NEAR(levels.project(particles), 0.08, 1e-12);  // the first link moves x8 by 0.08
  EXPECT_NEAR(distance(particles, 0, 8), 8 * kSpacing, 1e-12);
  for (int i = 0; i < 8; ++i) EXPECT_LT(particles.position[i].x(), particles.position[i + 1].x());
}

// The same on a sheet stretched by 10 % in every direction: the far corners come back to within
// 1 % of their rest distance from the pinned corner (the diagonals of the finer levels move them
// a little after the coarsest level put them there), and nothing pinned moves.
TEST(CoarseLevels, OneSweepBringsAStretchedSheetsCornersBack) {
  Particles particles = scaledGrid(1.1);
  CoarseLevels levels;
  levels.build(9, 9, kSpacing, 3);
  const Vec3 pinned = particles.position[0];
  levels.prepareStep(particles);
  EXPECT_GT(levels.project(particles), 0.0);
  EXPECT_EQ(particles.position[0], pinned);
  EXPECT_LE(distance(particles, 0, 8), 8 * kSpacing * 1.01);
  EXPECT_LE(distance(particles, 0, 72), 8 * kSpacing * 1.01);
  EXPECT_LE(distance(particles, 0, 80), 8 * std::sqrt(2.0) * kSpacing * 1.01);
}

// The swinging benchmark in small: a flat 33 x 33 cloth, both diagonals, no bending, swinging
// from two corners. With the levels its structural links are less stretched at the same substeps
// (the largest structural strain averaged over the last half second, as the final value alone
// swings with the cloth), its energy stays below the start's (no gain), and a run is bit for bit
// the same twice.
SceneConfig swingingCloth(int levels) {
  SceneConfig scene = test::clothScene(33, 33, 1.0 / 32, Method::kXpbd);
  scene.cloth.mass = 0.5;
  scene.cloth.origin = Eigen::Vector3d(0.0, 0.0, 1.5);
  scene.cloth.shear_diagonals = 2;
  scene.cloth.pinned = {0, 32};
  scene.solver.substeps = 10;
  scene.solver.damping = 0.1;
  scene.solver.levels = levels;
  return scene;
}

struct Swing {
  double late_max_strain = 0.0;  // structural max strain averaged over the last 30 steps
  Metrics end;
  Vec3Array positions;
};

Swing swing(const SceneConfig& scene) {
  Simulation sim(scene);
  Swing out;
  for (int k = 0; k < 90; ++k) {
    sim.step();
    if (k >= 60) out.late_max_strain += sim.computeMetrics().structural_max_strain / 30.0;
  }
  out.end = sim.computeMetrics();
  out.positions = sim.particles().position;
  return out;
}

TEST(CoarseLevels, SwingingClothStretchesLessAtEqualSubsteps) {
  const double start_energy = Simulation(swingingCloth(0)).computeMetrics().energy;
  const Swing plain = swing(swingingCloth(0));
  const Swing levels = swing(swingingCloth(4));
  const Swing again = swing(swingingCloth(4));
  ASSERT_TRUE(plain.end.finite && levels.end.finite);
  std::printf(
      "33 x 33 swinging, 10 substeps, last 0.5 s: structural max strain %.4g plain, "
      "%.4g with 4 levels; energy at 1.5 s %.4f, %.4f (start %.4f)\n",
      plain.late_max_strain, levels.late_max_strain, plain.end.energy, levels.end.energy,
      start_energy);
  EXPECT_LT(levels.late_max_strain, 0.7 * plain.late_max_strain);
  EXPECT_LT(levels.end.energy, start_energy);
  EXPECT_EQ(levels.positions, again.positions);
}

TEST(CoarseLevels, ReadFromTheScene) {
  const SceneConfig scene =
      sceneFromYaml(YAML::Load("solver: {levels: 3}\n"
                               "cloth: {rows: 8, cols: 8, shear_diagonals: 2}"));
  EXPECT_EQ(scene.solver.levels, 3);
  EXPECT_EQ(scene.cloth.shear_diagonals, 2);
  const SceneConfig defaults = sceneFromYaml(YAML::Load(""));
  EXPECT_EQ(defaults.solver.levels, 0);
  EXPECT_EQ(defaults.cloth.shear_diagonals, 1);
}

TEST(CoarseLevels, RefusedWhereTheyDoNotHold) {
  SceneConfig scene = swingingCloth(3);
  EXPECT_NO_THROW(validate(scene));
  scene.cloth.stretch_compliance = 1e-6;
  try {
    validate(scene);
    FAIL() << "a compliant cloth with levels was accepted";
  } catch (const ConfigError& e) {
    EXPECT_EQ(e.key(), "solver.levels");
  }
  scene = swingingCloth(17);
  EXPECT_THROW(validate(scene), ConfigError);
}

}  // namespace
}  // namespace pbd_cloth
