// The seed's scheme: Verlet integration, the box (C1) and stick (C2) constraints satisfied by
// projection, the relaxation loop and its adaptive iteration count.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <set>
#include <utility>

#include "pbd_cloth/sim/metrics.h"
#include "pbd_cloth/sim/simulation.h"
#include "test_scenes.h"

namespace pbd_cloth {
namespace {

// REFERENCE_CASES.md case 1: Verlet started with x_prev = x0 - v0 dt + g dt^2/2 is exact.
TEST(Verlet, FreeFallIsExact) {
  SceneConfig scene = test::clothScene(1, 2, 0.1, Method::kVerlet);
  Simulation sim(scene);
  const double z0 = sim.particles().position[0].z();
  for (int k = 0; k < 60; ++k) sim.step();
  const double t = 1.0;
  const double exact = z0 - 0.5 * 9.81 * t * t;
  EXPECT_NEAR(sim.particles().position[0].z(), exact, 1e-12);
  EXPECT_NEAR(sim.particles().position[1].z(), exact, 1e-12);
}

// Case 1, other half: the PBD prediction (v += g dt; x += v dt) is off by exactly g dt t / 2.
TEST(Verlet, PbdPredictionLagsByHalfAStep) {
  for (Method method : {Method::kPbd, Method::kXpbd}) {
    Simulation sim(test::clothScene(1, 2, 0.1, method));
    const double z0 = sim.particles().position[0].z();
    for (int k = 0; k < 60; ++k) sim.step();
    const double exact = z0 - 0.5 * 9.81;
    EXPECT_NEAR(exact - sim.particles().position[0].z(), 0.08175, 1e-9) << toString(method);
  }
}

// The seed's stick of length 100 in the box (0,0,0)-(1000,1000,1000), thrown into a corner so the
// box pushes both ends: after relaxation it keeps its length and stays inside.
SceneConfig stickInBox() {
  SceneConfig scene = test::clothScene(1, 2, 100.0, Method::kVerlet);
  scene.solver.iterations = 20;
  scene.solver.gravity = Eigen::Vector3d(0.0, 0.0, -981.0);  // units of the seed's box
  scene.cloth.origin = Eigen::Vector3d(900.0, 500.0, 300.0);
  scene.cloth.rpy = Eigen::Vector3d(0.0, -0.6, 0.0);  // tilted: one end hits the floor first
  scene.bounds.enabled = true;
  scene.bounds.min = Eigen::Vector3d(0.0, 0.0, 0.0);
  scene.bounds.max = Eigen::Vector3d(1000.0, 1000.0, 1000.0);
  return scene;
}

TEST(Verlet, StickInBoxKeepsLengthAndStaysInside) {
  Simulation sim(stickInBox());
  // Throw it towards the x = 1000 wall so the wall and the floor both push it.
  for (auto& v : sim.mutableParticles().velocity) v = Vec3(600.0, 0.0, 0.0);
  double max_length_error = 0.0, max_x = 0.0;
  for (int k = 0; k < 300; ++k) {
    sim.step();
    const auto& x = sim.particles().position;
    max_x = std::max({max_x, x[0].x(), x[1].x()});
    for (const auto& p : x) {
      ASSERT_GE(p.minCoeff(), 0.0) << "step " << k;
      ASSERT_LE(p.maxCoeff(), 1000.0) << "step " << k;
    }
    max_length_error = std::max(max_length_error, std::abs((x[0] - x[1]).norm() - 100.0));
  }
  const auto& x = sim.particles().position;
  EXPECT_LT(max_length_error, 1e-3 * 100.0);
  // It hit the wall (the box pushed it) and came to rest lying on the floor.
  EXPECT_DOUBLE_EQ(max_x, 1000.0);
  EXPECT_NEAR(x[0].z(), 0.0, 1e-9);
  EXPECT_NEAR(x[1].z(), 0.0, 1e-9);
  EXPECT_NEAR((x[0] - x[1]).norm(), 100.0, 1e-6);
}

// The box alone would leave the stick at the wrong length; the relaxation loop must repeat both.
TEST(Verlet, OnePassLeavesErrorThatRelaxationRemoves) {
  auto run = [](int iterations) {
    SceneConfig scene = stickInBox();
    scene.solver.iterations = iterations;
    scene.cloth.origin = Eigen::Vector3d(890.0, 500.0, 500.0);
    scene.cloth.rpy = Eigen::Vector3d(0.0, 0.0, 0.0);
    scene.solver.gravity.setZero();
    Simulation sim(scene);
    // Then moved so that its far end is outside the box (a scene may not start so: validate()
    // refuses a cloth outside its bounds, test_scene_yaml.cpp).
    for (auto& x : sim.mutableParticles().position) x.x() += 100.0;
    sim.step();
    const auto& x = sim.particles().position;
    return std::abs((x[0] - x[1]).norm() - 100.0);
  };
  const double one_pass = run(1), many = run(50);
  EXPECT_GT(one_pass, 1.0);  // 1 pass: the box undoes part of the stick correction
  EXPECT_LT(many, 1e-6);     // relaxation converges to both constraints at once
}

// Adaptive count: passes stop when the largest change of a pass is below solver.tolerance.
TEST(Verlet, AdaptiveIterationsStopEarlyAtRestAndRunLongerWhenDisturbed) {
  SceneConfig scene = test::clothScene(10, 10, 0.05, Method::kVerlet);
  scene.solver.iterations = 1000;
  scene.solver.tolerance = 1e-5;
  scene.solver.gravity.setZero();
  Simulation sim(scene);
  sim.step();
  const int resting = sim.stats().iterations;
  EXPECT_EQ(resting, 1);  // nothing to correct: one pass measures zero change

  sim.mutableParticles().velocity[55] = Vec3(0.0, 0.0, 0.5);  // kick the middle
  sim.step();
  const int disturbed = sim.stats().iterations;
  EXPECT_GT(disturbed, 10);
  EXPECT_LT(disturbed, 1000);  // stopped by the tolerance, not by the cap
  // The extra passes are what make the error small: one pass leaves far more strain.
  const double adaptive_strain = sim.stats().max_strain;
  SceneConfig one_pass_scene = scene;
  one_pass_scene.solver.iterations = 1;
  Simulation one_pass(one_pass_scene);
  one_pass.step();
  one_pass.mutableParticles().velocity[55] = Vec3(0.0, 0.0, 0.5);
  one_pass.step();
  EXPECT_LT(adaptive_strain, 0.2 * one_pass.stats().max_strain);
  std::printf("resting %d passes, disturbed %d passes, strain %.2e (one pass %.2e)\n", resting,
              disturbed, adaptive_strain, one_pass.stats().max_strain);

  // Without a tolerance every pass runs.
  scene.solver.tolerance = 0.0;
  Simulation fixed(scene);
  fixed.step();
  EXPECT_EQ(fixed.stats().iterations, 1000);
}

// A cloth resting on the floor of the box: one pass lifts it back, the next changes nothing.
TEST(Verlet, AdaptiveIterationsOnRestingClothOnFloor) {
  SceneConfig scene = test::clothScene(8, 8, 0.05, Method::kVerlet);
  scene.solver.iterations = 50;
  scene.solver.tolerance = 1e-9;
  scene.bounds.enabled = true;
  scene.bounds.min = Eigen::Vector3d(-10, -10, 0.0);
  Simulation sim(scene);
  for (int k = 0; k < 10; ++k) sim.step();
  EXPECT_LE(sim.stats().iterations, 2);
  for (const auto& p : sim.particles().position) EXPECT_NEAR(p.z(), 0.0, 1e-12);
}

// Grid construction: rows x cols particles, pinned ones stay, triangles and constraint counts.
TEST(ClothGrid, CountsAndPins) {
  SceneConfig scene = test::clothScene(5, 7, 0.1, Method::kXpbd);
  scene.cloth.pinned = {0, 6};
  scene.cloth.bend_compliance = 0.0;
  Simulation sim(scene);
  EXPECT_EQ(sim.particles().size(), 35);
  EXPECT_EQ(sim.topology().triangleCount(), 2 * 4 * 6);
  EXPECT_EQ(sim.topology().structural_count, 5 * 6 + 4 * 7);
  EXPECT_EQ(static_cast<int>(sim.topology().stretch.size()), 5 * 6 + 4 * 7 + 4 * 6);
  // Interior edges: all edges minus the boundary ones.
  const int edges = 5 * 6 + 4 * 7 + 4 * 6;
  const int boundary = 2 * (4 + 6);
  EXPECT_EQ(static_cast<int>(sim.topology().bend.size()), edges - boundary);
  const Vec3 p0 = sim.particles().position[0], p6 = sim.particles().position[6];
  for (int k = 0; k < 30; ++k) sim.step();
  EXPECT_EQ(sim.particles().position[0], p0);
  EXPECT_EQ(sim.particles().position[6], p6);
  EXPECT_LT(sim.particles().position[34].z(), -0.1);  // the free corner fell
}

// cloth.shear_diagonals: 2 adds the second diagonal of every cell, after the structural links
// (which stay first, so the structural strain is still stretch[0, structural_count)); each of them
// is a cell diagonal at its rest length, and no link appears twice.
TEST(ClothGrid, BothDiagonalsPerCell) {
  SceneConfig scene = test::clothScene(5, 7, 0.1, Method::kXpbd);
  scene.cloth.shear_diagonals = 2;
  Simulation sim(scene);
  const ClothTopology& topology = sim.topology();
  EXPECT_EQ(topology.structural_count, 5 * 6 + 4 * 7);
  ASSERT_EQ(static_cast<int>(topology.stretch.size()), 5 * 6 + 4 * 7 + 2 * 4 * 6);
  std::set<std::pair<int, int>> seen;
  for (std::size_t c = 0; c < topology.stretch.size(); ++c) {
    const DistanceConstraint& con = topology.stretch[c];
    const int dr = std::abs(con.i / 7 - con.j / 7), dc = std::abs(con.i % 7 - con.j % 7);
    const bool structural = static_cast<int>(c) < topology.structural_count;
    EXPECT_EQ(dr + dc, structural ? 1 : 2) << "constraint " << c;
    if (!structural) EXPECT_TRUE(dr == 1 && dc == 1) << "constraint " << c;
    EXPECT_NEAR(con.rest_length, structural ? 0.1 : 0.1 * std::sqrt(2.0), 1e-12);
    EXPECT_TRUE(seen.emplace(std::min(con.i, con.j), std::max(con.i, con.j)).second)
        << "constraint " << c << " repeats a link";
  }
  // The triangles are those of one diagonal: the second diagonal is a link, not a mesh edge.
  EXPECT_EQ(topology.triangleCount(), 2 * 4 * 6);
}

// The structural strain leaves the shear links out: stretching only the diagonals of a cloth
// changes max_strain but not structural_max_strain.
TEST(ClothGrid, StructuralStrainCountsRowsAndColumnsOnly) {
  SceneConfig scene = test::clothScene(3, 3, 0.1, Method::kXpbd);
  scene.cloth.shear_diagonals = 2;
  Simulation sim(scene);
  Particles particles = sim.particles();
  ClothTopology topology = sim.topology();
  for (std::size_t c = topology.structural_count; c < topology.stretch.size(); ++c) {
    topology.stretch[c].rest_length *= 0.5;  // every diagonal now reads strain 1
  }
  double max_all = 0.0, mean_all = 0.0, max_structural = 1.0, mean_structural = 1.0;
  computeStrain(particles, topology, max_all, mean_all);
  computeStructuralStrain(particles, topology, max_structural, mean_structural);
  EXPECT_NEAR(max_all, 1.0, 1e-12);
  EXPECT_NEAR(mean_all, 8.0 / (12.0 + 8.0), 1e-12);  // 8 diagonals of 20 links
  EXPECT_NEAR(max_structural, 0.0, 1e-12);
  EXPECT_NEAR(mean_structural, 0.0, 1e-12);
  // Stretching one structural link shows in both.
  particles.position[2].x() += 0.01;  // particle (0, 2): link (0,1)-(0,2) is 0.11 m long
  computeStructuralStrain(particles, topology, max_structural, mean_structural);
  EXPECT_NEAR(max_structural, 0.1, 1e-9);
}

// Links between two kinematic particles (pinned or grasped: placed by their pins or grippers, not
// by the solver) are left out of the strain: two grippers that hold neighbouring particles apart
// are not the solver's error.
TEST(ClothGrid, StrainLeavesOutLinksBetweenTwoKinematicParticles) {
  SceneConfig scene = test::clothScene(3, 3, 0.1, Method::kXpbd);
  scene.cloth.pinned = {};
  Simulation sim(scene);
  Particles particles = sim.particles();
  const ClothTopology& topology = sim.topology();
  particles.position[0].x() -= 0.01;  // link (0,0)-(0,1) is 0.11 m long, (0,0)-(1,0) 0.1005 m
  particles.inverse_mass[0] = 0.0;    // (0, 0) kinematic, (0, 1) free: the link counts
  double max_structural = 0.0, mean_structural = 0.0, max_all = 0.0, mean_all = 0.0;
  computeStructuralStrain(particles, topology, max_structural, mean_structural);
  EXPECT_NEAR(max_structural, 0.1, 1e-9);
  particles.inverse_mass[1] = 0.0;  // both kinematic: that link is left out
  computeStructuralStrain(particles, topology, max_structural, mean_structural);
  computeStrain(particles, topology, max_all, mean_all);
  const double column = std::sqrt(1.01) - 1.0;  // (0,0)-(1,0), the largest strain left
  EXPECT_NEAR(max_structural, column, 1e-9);
  EXPECT_NEAR(mean_structural, column / 11.0, 1e-9);  // 11 of the 12 structural links count
  // Over every link: the diagonal (0,0)-(1,1), 0.1 m across and 0.11 m along, not the 10 %.
  EXPECT_NEAR(max_all, std::hypot(0.11, 0.1) / std::hypot(0.1, 0.1) - 1.0, 1e-9);
}

TEST(ClothGrid, RopeHasNoTriangles) {
  Simulation sim(test::clothScene(1, 20, 0.05, Method::kXpbd));
  EXPECT_EQ(sim.topology().triangleCount(), 0);
  EXPECT_EQ(static_cast<int>(sim.topology().stretch.size()), 19);
}

}  // namespace
}  // namespace pbd_cloth
