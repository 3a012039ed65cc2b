// Inputs that break naive code (issue 3 point 3, REFERENCE_CASES.md "Inputs that break naive
// code"): coincident particles, constraints whose particles are all kinematic (0/0 with
// alpha = 0), zero-area triangles, flat and fully folded hinges, a scene 1e4 m from the origin.
// Every method and ordering must keep positions finite, skip what has no direction instead of
// dividing by zero, and leave kinematic particles exactly where they were put.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <limits>
#include <vector>

#include "accuracy_helpers.h"
#include "pbd_cloth/sim/cloth_builder.h"
#include "pbd_cloth/sim/simulation.h"

namespace pbd_cloth {
namespace {

using test::kPi;

struct Variant {
  Method method;
  Ordering ordering;
};

std::vector<Variant> allVariants() {
  std::vector<Variant> out;
  for (Method method : {Method::kVerlet, Method::kPbd, Method::kXpbd, Method::kMassSpring}) {
    for (Ordering ordering : {Ordering::kGaussSeidel, Ordering::kJacobi}) {
      out.push_back({method, ordering});
    }
  }
  return out;
}

std::string name(const Variant& v) {
  return std::string(toString(v.method)) + "/" + toString(v.ordering);
}

// A cloth with bending, at 60 Hz x 4 substeps x 4 passes, for every variant.
SceneConfig degenerateScene(int rows, int cols, const Variant& v) {
  SceneConfig scene = test::clothScene(rows, cols, 0.1, v.method);
  scene.solver.ordering = v.ordering;
  scene.solver.substeps = 4;
  scene.solver.iterations = 4;
  scene.solver.spring_stiffness = 1e3;  // mass_spring: stable at h = 1/240 s for 1 kg particles
  scene.cloth.bend_compliance = 0.0;    // rigid bending: the most demanding hinge solve
  scene.solver.bend_stiffness = 1.0;
  return scene;
}

void expectFinite(const Simulation& sim, const std::string& what) {
  const Particles& p = sim.particles();
  for (int i = 0; i < p.size(); ++i) {
    ASSERT_TRUE(p.position[i].allFinite()) << what << " particle " << i;
    ASSERT_TRUE(p.velocity[i].allFinite()) << what << " particle " << i;
  }
}

// Two neighbours on the same spot: their constraint has no direction (|delta| = 0) and is skipped
// for that pass; the other constraints pull them apart again.
TEST(Robustness, CoincidentNeighboursSeparateAgain) {
  for (const Variant& v : allVariants()) {
    SceneConfig scene = degenerateScene(5, 5, v);
    scene.cloth.pinned = {0, 4};
    Simulation sim(scene);
    sim.mutableParticles().position[12] = sim.particles().position[13];
    for (int k = 0; k < 60; ++k) {
      sim.step();
      expectFinite(sim, name(v));
    }
    EXPECT_GT((sim.particles().position[12] - sim.particles().position[13]).norm(), 0.05)
        << name(v);
    EXPECT_EQ(sim.stats().degenerate_constraints, 0) << name(v) << ": separated again";
    EXPECT_EQ(sim.stats().first_degenerate_constraint, -1) << name(v);
  }
}

// Every particle on one point, two of them pinned there: all stretch constraints have zero length,
// every hinge is flat (b = 0), the constraint between the pins has two kinematic ends.
TEST(Robustness, ClothCollapsedToOnePointStaysFinite) {
  for (const Variant& v : allVariants()) {
    SceneConfig scene = degenerateScene(4, 4, v);
    scene.cloth.pinned = {0, 1};
    Simulation sim(scene);
    for (Vec3& x : sim.mutableParticles().position) x = Vec3(0.3, -0.2, 1.0);
    for (int k = 0; k < 30; ++k) {
      sim.step();
      expectFinite(sim, name(v));
    }
    EXPECT_EQ(sim.particles().position[0], Vec3(0.3, -0.2, 1.0)) << name(v);
    EXPECT_EQ(sim.particles().position[1], Vec3(0.3, -0.2, 1.0)) << name(v);
  }
}

// Two free particles on one spot, falling together: their one constraint never gets a direction.
// Every step reports exactly it, and both stay finite and together.
TEST(Robustness, CoincidentPairIsReportedEveryStep) {
  for (const Variant& v : allVariants()) {
    SceneConfig scene = degenerateScene(1, 2, v);
    scene.cloth.pinned.clear();
    Simulation sim(scene);
    ASSERT_EQ(sim.topology().stretch.size(), 1u);
    sim.mutableParticles().position[1] = sim.particles().position[0];
    for (int k = 0; k < 10; ++k) {
      sim.step();
      expectFinite(sim, name(v));
      EXPECT_EQ(sim.stats().degenerate_constraints, 1) << name(v) << " step " << k;
      EXPECT_EQ(sim.stats().first_degenerate_constraint, 0) << name(v) << " step " << k;
    }
    EXPECT_EQ(sim.particles().position[0], sim.particles().position[1]) << name(v);
  }
}

// A violated constraint between two pinned particles (rigid, alpha = 0): its generalized inverse
// mass is 0 and the step would be 0/0. Skipped: the pins stay exactly where they were put and the
// free particle hangs from the second pin at its rest length.
TEST(Robustness, ConstraintBetweenTwoKinematicParticlesIsSkipped) {
  for (const Variant& v : allVariants()) {
    if (v.method == Method::kMassSpring) continue;  // springs: no projection, checked below
    SceneConfig scene = degenerateScene(1, 3, v);
    scene.cloth.pinned = {0, 1};
    scene.solver.iterations = 20;
    Simulation sim(scene);
    const Vec3 moved = sim.particles().position[1] + Vec3(0.1, 0.0, 0.05);
    sim.mutableParticles().position[1] = moved;
    const Vec3 first = sim.particles().position[0];
    for (int k = 0; k < 120; ++k) {
      sim.step();
      expectFinite(sim, name(v));
    }
    EXPECT_EQ(sim.particles().position[0], first) << name(v);
    EXPECT_EQ(sim.particles().position[1], moved) << name(v);
    EXPECT_NEAR((sim.particles().position[2] - moved).norm(), 0.1, 1e-3) << name(v);
  }
  // Every particle of a hinge kinematic: the bending step's denominator is 0 too.
  for (const Variant& v : allVariants()) {
    SceneConfig scene = degenerateScene(2, 2, v);
    scene.cloth.pinned = {0, 1, 2, 3};
    Simulation sim(scene);
    sim.mutableParticles().position[3].z() += 0.05;  // bent and stretched
    const Vec3Array put = sim.particles().position;
    for (int k = 0; k < 10; ++k) sim.step();
    EXPECT_TRUE(sim.particles().position == put) << name(v);
  }
}

// Zero-area triangles. At build time a hinge on a degenerate (collinear or coincident) triangle
// is refused, not given infinite cotangent weights; at run time a cloth flattened onto a line has
// only zero-area triangles and must still step.
TEST(Robustness, ZeroAreaTriangles) {
  const Vec3Array rest = {Vec3(0, 0, 0),    Vec3(1, 0, 0), Vec3(0.5, 0, 0),
                          Vec3(0.5, -1, 0), Vec3(0, 0, 0), Vec3(1e-9, 1e-9, 0)};
  BendConstraint bend;
  EXPECT_FALSE(makeBendConstraint(rest, 0, 1, 2, 3, bend));  // x2 on the edge: zero area
  EXPECT_FALSE(makeBendConstraint(rest, 0, 1, 3, 4, bend));  // x3 = x0
  EXPECT_FALSE(makeBendConstraint(rest, 0, 4, 1, 3, bend));  // zero-length edge
  EXPECT_TRUE(makeBendConstraint(rest, 1, 0, 3, 5, bend));   // proper (if thin) triangles
  // One triangle listed twice (a mesh's duplicate): no hinge, so a hinge's corners are always
  // four particles (flat_hinges.h).
  EXPECT_FALSE(makeBendConstraint(rest, 0, 1, 3, 3, bend));
  // Relative, not absolute, thresholds: a 1e-6 m cloth still gets its hinges.
  const Vec3Array tiny = {Vec3(0, 0, 0), Vec3(1e-6, 0, 0), Vec3(0, -1e-6, 0), Vec3(1e-6, 1e-6, 0)};
  EXPECT_TRUE(makeBendConstraint(tiny, 0, 1, 2, 3, bend));
  for (double w : bend.weight) EXPECT_TRUE(std::isfinite(w));
  EXPECT_TRUE(std::isfinite(bend.scale));
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const Vec3Array broken = {Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(nan, 0, 0), Vec3(0, -1, 0)};
  EXPECT_FALSE(makeBendConstraint(broken, 0, 1, 2, 3, bend));

  for (const Variant& v : allVariants()) {
    SceneConfig scene = degenerateScene(4, 4, v);
    scene.cloth.pinned = {0};
    Simulation sim(scene);
    Particles& p = sim.mutableParticles();
    for (int i = 0; i < p.size(); ++i) p.position[i] = Vec3(0.1 * (i % 4) + 0.05 * (i / 4), 0, 0);
    for (int k = 0; k < 60; ++k) {
      sim.step();
      expectFinite(sim, name(v));
    }
  }
}

// A flat hinge has b = 0 and no gradient direction: skipped, so a flat cloth without gravity
// stays bit-identical. A fully folded one (two triangles on top of each other) has a large but
// finite b (isometric bending is quadratic in the positions: no angle, no acos, no singularity).
TEST(Robustness, FlatAndFullyFoldedHinges) {
  for (const Variant& v : allVariants()) {
    SceneConfig scene = degenerateScene(6, 6, v);
    scene.solver.gravity.setZero();
    Simulation sim(scene);
    const Vec3Array flat = sim.particles().position;
    for (int k = 0; k < 20; ++k) sim.step();
    EXPECT_TRUE(sim.particles().position == flat) << name(v);
  }
  for (const Variant& v : allVariants()) {
    // 2 x 2 grid: triangles (0,2,3) and (0,3,1) share the diagonal 0-3; reflecting particle 1
    // across it lands on particle 2, folding the hinge by 180 degrees.
    SceneConfig scene = degenerateScene(2, 2, v);
    scene.solver.gravity.setZero();
    scene.cloth.pinned = {0, 3};
    Simulation sim(scene);
    ASSERT_EQ(sim.topology().bend.size(), 1u);
    sim.mutableParticles().position[1] = sim.particles().position[2];
    for (int k = 0; k < 60; ++k) {
      sim.step();
      expectFinite(sim, name(v));
    }
    // The fold is a symmetric state of the isometric energy (x1 and x2 get the same correction),
    // so it need not open, and rigid bending (k = 1, alpha = 0) against rigid stretch has no
    // exact solution there; the particles must stay finite and near the pins, that is all.
    for (const Vec3& x : sim.particles().position) EXPECT_LT(x.norm(), 1.0) << name(v);
  }
}

// A scene 1e4 m from the origin behaves as the same scene at the origin (double precision: the
// unit in the last place at 1e4 m is 1.8e-12 m, against substep increments g h^2 ~ 1.7e-4 m here
// and ~2.7e-7 m below, which float32 with its 1e-3 m spacing would round away). Same hanging
// cloth, shifted. With tethers the top row between the pins is taut: its particles must lie in
// the intersection of two balls that only touch, and a rounding change delta of the pin distance
// opens that point into a circle of radius sqrt(2 r delta) ~ 1e-6 m (a taut string sags by
// sqrt(L delta) when its ends come delta closer), which the swinging cloth then carries along: the
// far scene agrees to 1e-4 m there, to 1e-8 m without tethers.
TEST(Robustness, SceneFarFromOriginMatchesSceneAtOrigin) {
  const Vec3 offset(5e3, -5e3, 1e4);
  for (bool tethers : {false, true}) {
    for (const Variant& v : allVariants()) {
      SceneConfig scene = degenerateScene(8, 8, v);
      scene.cloth.rpy = Eigen::Vector3d(kPi / 2.0, 0.0, 0.0);
      scene.cloth.pinned = {0, 7};
      scene.cloth.bend_compliance = 1e-2;
      scene.cloth.tethers = tethers;
      SceneConfig far = scene;
      far.cloth.origin += offset;
      Simulation near_sim(scene), far_sim(far);
      double difference = 0.0;
      for (int k = 0; k < 60; ++k) {
        near_sim.step();
        far_sim.step();
        for (int i = 0; i < near_sim.particles().size(); ++i) {
          difference = std::max(
              difference,
              (far_sim.particles().position[i] - offset - near_sim.particles().position[i]).norm());
        }
      }
      expectFinite(far_sim, name(v));
      std::printf("%s, tethers %d: largest difference far - near %.2e m\n", name(v).c_str(),
                  tethers, difference);
      const double tolerance = tethers ? 1e-4 : 1e-8;
      EXPECT_LT(difference, tolerance) << name(v) << " tethers " << tethers;
      EXPECT_NEAR(far_sim.stats().max_strain, near_sim.stats().max_strain, 1e3 * tolerance)
          << name(v) << " tethers " << tethers;
    }
  }
  // Free fall there at 60 Hz x 100 substeps: the PBD prediction lags the exact parabola by
  // g h t / 2 with h the substep (REFERENCE_CASES.md case 1); nothing of the 2.7e-7 m steps is
  // lost.
  SceneConfig scene = test::clothScene(1, 2, 0.1, Method::kXpbd);
  scene.cloth.origin = offset;
  scene.solver.substeps = 100;
  Simulation sim(scene);
  for (int k = 0; k < 60; ++k) sim.step();
  const double h = 1.0 / 6000.0, g = 9.81;
  const double expected = offset.z() - 0.5 * g - 0.5 * g * h;
  std::printf(
      "free fall 1e4 m from the origin, 60 Hz x 100 substeps, 1 s: error %.2e m against "
      "z0 - g t^2/2 - g h t/2\n",
      sim.particles().position[0].z() - expected);
  EXPECT_NEAR(sim.particles().position[0].z(), expected, 1e-9);
}

// Live poses that cannot be right are refused by the simulation itself, whoever calls it (the
// node checks them first and counts them; cloth_bench, the fuzzers and other programs rely on
// this): NaN, Inf, a zero quaternion, a position beyond 10 km. The gripper, obstacle and link
// keep their course and the state stays finite; a good pose afterwards is taken.
TEST(Robustness, ImpossibleLivePosesAreRefusedAndTheStateStaysFinite) {
  SceneConfig scene;
  scene.cloth.rows = scene.cloth.cols = 6;
  scene.cloth.spacing = 0.05;
  scene.cloth.origin = Eigen::Vector3d::Zero();  // particle 0 at the gripper's start, the origin
  scene.cloth.pinned = {5};
  GripperConfig hand;
  hand.name = "hand";
  hand.radius = 0.08;
  scene.grippers.push_back(hand);
  ObstacleConfig ball;
  ball.name = "ball";
  scene.obstacles.push_back(ball);
  Simulation sim(scene);
  ASSERT_TRUE(sim.setGrasp(0, true).success);
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const double inf = std::numeric_limits<double>::infinity();
  std::vector<Pose> bad(4);
  bad[0].position = Eigen::Vector3d(nan, 0.0, 0.0);
  bad[1].position = Eigen::Vector3d(0.0, inf, 0.0);
  bad[2].orientation = Eigen::Quaterniond(0.0, 0.0, 0.0, 0.0);
  bad[3].position = Eigen::Vector3d(0.0, 0.0, 1e300);
  for (const Pose& pose : bad) {
    EXPECT_FALSE(poseProblem(pose).empty());
    EXPECT_FALSE(sim.setGripperPose(0, pose));
    EXPECT_FALSE(sim.setObstaclePose(0, pose));
    sim.step();
  }
  EXPECT_NE(poseProblem(bad[3]).find("from the scene origin"), std::string::npos);
  for (const Vec3& x : sim.particles().position) ASSERT_TRUE(x.allFinite());
  Pose good;
  good.position = Eigen::Vector3d(0.1, 0.0, 0.2);
  good.orientation = Eigen::Quaterniond(2.0, 0.0, 0.0, 0.0);  // not unit: normalised, taken
  EXPECT_TRUE(poseProblem(good).empty());
  EXPECT_TRUE(sim.setGripperPose(0, good));
  EXPECT_TRUE(sim.setObstaclePose(0, good));
  sim.step();
  EXPECT_NEAR(sim.grippers().pose(0).position.x(), 0.1, 1e-12);
  EXPECT_NEAR(sim.grippers().pose(0).orientation.norm(), 1.0, 1e-12);
}

}  // namespace
}  // namespace pbd_cloth
