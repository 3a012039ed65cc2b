// solver.levels: the hierarchy of long-range links (coarse_levels.h) on grid cloths.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

#include "pbd_cloth/cloth_builder.h"
#include "pbd_cloth/coarse_levels.h"
#include "pbd_cloth/metrics.h"
#include "pbd_cloth/scene_yaml.h"
#include "pbd_cloth/simulation.h"
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
  for (bool interpolate : {false, true}) {
    Particles particles = scaledGrid(0.5);
    const Vec3Array before = particles.position;
    CoarseLevels levels;
    levels.build(9, 9, kSpacing, 3);
    EXPECT_EQ(levels.project(particles, interpolate), 0.0);
    EXPECT_EQ(particles.position, before) << "interpolate " << interpolate;
  }
}

// A cloth stretched by 10 % in every direction: one sweep brings the far corners back within
// their rest distance of the pinned corner (to rounding), moves nothing pinned, and leaves the
// cloth's own links less stretched than before.
TEST(CoarseLevels, OneSweepRemovesAStretchSpreadOverTheCloth) {
  Particles particles = scaledGrid(1.1);
  SceneConfig scene = test::clothScene(9, 9, kSpacing, Method::kXpbd);
  Particles rest;
  ClothTopology topology;
  buildScene(scene, rest, topology);
  double max_before = 0.0, mean_before = 0.0, max_after = 0.0, mean_after = 0.0;
  computeStrain(particles, topology, max_before, mean_before);
  CoarseLevels levels;
  levels.build(9, 9, kSpacing, 3);
  const Vec3 pinned = particles.position[0];
  EXPECT_GT(levels.project(particles, false), 0.0);
  EXPECT_EQ(particles.position[0], pinned);
  EXPECT_LE(distance(particles, 0, 8), 8 * kSpacing * (1.0 + 1e-9));
  EXPECT_LE(distance(particles, 0, 72), 8 * kSpacing * (1.0 + 1e-9));
  EXPECT_LE(distance(particles, 0, 80), 8 * std::sqrt(2.0) * kSpacing * (1.0 + 1e-9));
  computeStrain(particles, topology, max_after, mean_after);
  EXPECT_NEAR(mean_before, 0.1, 1e-9);
  EXPECT_LT(mean_after, 0.5 * mean_before);
}

// The swinging benchmark in small: a flat 17 x 17 cloth, both diagonals, no bending, swinging
// from two corners for 1 s. With the levels its structural links end less stretched at the same
// substeps, its energy stays below the start's (no gain), and it runs bit for bit the same twice.
SceneConfig swingingCloth(int levels) {
  SceneConfig scene = test::clothScene(17, 17, 1.0 / 16, Method::kXpbd);
  scene.cloth.mass = 0.5;
  scene.cloth.origin = Eigen::Vector3d(0.0, 0.0, 1.5);
  scene.cloth.shear_diagonals = 2;
  scene.cloth.pinned = {0, 16};
  scene.solver.substeps = 8;
  scene.solver.damping = 0.1;
  scene.solver.levels = levels;
  return scene;
}

Metrics swing(const SceneConfig& scene, Vec3Array* positions = nullptr) {
  Simulation sim(scene);
  for (int k = 0; k < 60; ++k) sim.step();
  if (positions) *positions = sim.particles().position;
  return sim.computeMetrics();
}

TEST(CoarseLevels, SwingingClothStretchesLessAtEqualSubsteps) {
  const double start_energy = Simulation(swingingCloth(0)).computeMetrics().energy;
  const Metrics plain = swing(swingingCloth(0));
  Vec3Array first, second;
  const Metrics levels = swing(swingingCloth(3), &first);
  swing(swingingCloth(3), &second);
  ASSERT_TRUE(plain.finite && levels.finite);
  std::printf(
      "17 x 17 swinging, 8 substeps: structural max / mean strain %.4g / %.4g plain, "
      "%.4g / %.4g with 3 levels; energy %.4f, %.4f (start %.4f)\n",
      plain.structural_max_strain, plain.structural_mean_strain, levels.structural_max_strain,
      levels.structural_mean_strain, plain.energy, levels.energy, start_energy);
  EXPECT_LT(levels.structural_max_strain, 0.5 * plain.structural_max_strain);
  EXPECT_LT(levels.structural_mean_strain, plain.structural_mean_strain);
  EXPECT_LT(levels.energy, start_energy);
  EXPECT_EQ(first, second);
}

TEST(CoarseLevels, ReadFromTheScene) {
  const SceneConfig scene =
      sceneFromYaml(YAML::Load("solver: {levels: 3, levels_interpolate: true}\n"
                               "cloth: {rows: 8, cols: 8, shear_diagonals: 2}"));
  EXPECT_EQ(scene.solver.levels, 3);
  EXPECT_TRUE(scene.solver.levels_interpolate);
  EXPECT_EQ(scene.cloth.shear_diagonals, 2);
  const SceneConfig defaults = sceneFromYaml(YAML::Load(""));
  EXPECT_EQ(defaults.solver.levels, 0);
  EXPECT_FALSE(defaults.solver.levels_interpolate);
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
