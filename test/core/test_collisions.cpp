// Obstacles and the broad phase: signed distances of the four shapes, the spatial hash against
// brute force, no tunnelling (REFERENCE_CASES.md case 13), moving obstacles that push the cloth,
// the shipped drape scene, and overlaps the scene starts with.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <random>
#include <set>
#include <string>
#include <utility>
#include <vector>

#include "collision_scenes.h"
#include "pbd_cloth/geometry/shapes.h"
#include "pbd_cloth/geometry/spatial_hash.h"
#include "pbd_cloth/scene/scene_yaml.h"
#include "pbd_cloth/sim/metrics.h"
#include "pbd_cloth/sim/simulation.h"

namespace pbd_cloth {
namespace {

using test::kPoint;

Shape shapeOf(const ObstacleConfig& obstacle) { return makeShape(obstacle); }

TEST(CollisionShapes, SignedDistancesOfKnownPoints) {
  Vec3 n;
  const Shape ball = shapeOf(test::sphere("s", 0.5, test::makePose(Vec3::Zero())));
  EXPECT_DOUBLE_EQ(signedDistance(ball, Vec3(0.0, 2.0, 0.0), n), 1.5);
  EXPECT_TRUE(n.isApprox(Vec3::UnitY()));
  EXPECT_DOUBLE_EQ(signedDistance(ball, Vec3(0.0, 0.0, -0.2), n), -0.3);
  EXPECT_TRUE(n.isApprox(-Vec3::UnitZ()));

  // Box of size (2, 4, 6): half extents (1, 2, 3).
  const Shape box = shapeOf(test::box("b", Vec3(2.0, 4.0, 6.0), test::makePose(Vec3::Zero())));
  EXPECT_DOUBLE_EQ(signedDistance(box, Vec3(2.0, 0.0, 0.0), n), 1.0);
  EXPECT_TRUE(n.isApprox(Vec3::UnitX()));
  EXPECT_NEAR(signedDistance(box, Vec3(2.0, 3.0, 4.0), n), std::sqrt(3.0), 1e-15);  // corner
  EXPECT_TRUE(n.isApprox(Vec3(1.0, 1.0, 1.0).normalized()));
  EXPECT_DOUBLE_EQ(signedDistance(box, Vec3(0.0, 0.0, 0.0), n), -1.0);  // out through +-x
  EXPECT_DOUBLE_EQ(std::abs(n.x()), 1.0);
  EXPECT_DOUBLE_EQ(signedDistance(box, Vec3(0.5, -1.8, 0.0), n), -0.2);
  EXPECT_TRUE(n.isApprox(-Vec3::UnitY()));

  // Capsule: axis z, length 1 between the end-sphere centres, radius 0.1.
  const Shape rod = shapeOf(test::capsule("c", 0.1, 1.0, test::makePose(Vec3::Zero())));
  EXPECT_DOUBLE_EQ(signedDistance(rod, Vec3(0.3, 0.0, 0.2), n), 0.2);
  EXPECT_TRUE(n.isApprox(Vec3::UnitX()));
  EXPECT_NEAR(signedDistance(rod, Vec3(0.0, 0.0, 1.0), n), 0.4, 1e-15);  // beyond the end sphere
  EXPECT_TRUE(n.isApprox(Vec3::UnitZ()));

  // Plane given with a non-unit normal: n.p - offset >= 0 is the plane z = 1.
  const Shape floor = shapeOf(test::plane("p", Vec3(0.0, 0.0, 2.0), 2.0));
  EXPECT_DOUBLE_EQ(signedDistance(floor, Vec3(5.0, -3.0, 3.0), n), 2.0);
  EXPECT_TRUE(n.isApprox(Vec3::UnitZ()));
}

// Every shape: the distance is 1-Lipschitz (the sweep relies on it), the normal is unit, and
// stepping back by the distance along the normal lands on the surface.
TEST(CollisionShapes, DistanceIsExactAndLipschitz) {
  const Eigen::Quaterniond turn(Eigen::AngleAxisd(0.7, Vec3(1.0, 2.0, 3.0).normalized()));
  const ObstacleConfig configs[] = {
      test::sphere("s", 0.3, test::makePose(Vec3::Zero())),
      test::box("b", Vec3(0.4, 0.2, 0.6), test::makePose(Vec3::Zero(), turn)),
      test::capsule("c", 0.1, 0.5, test::makePose(Vec3::Zero(), turn)),
      test::plane("p", Vec3(1.0, -1.0, 2.0), 0.1)};
  std::mt19937 random(3);
  std::uniform_real_distribution<double> unit(-1.0, 1.0);
  for (const ObstacleConfig& config : configs) {
    const Shape shape = shapeOf(config);
    for (int k = 0; k < 2000; ++k) {
      const Vec3 x(unit(random), unit(random), unit(random)),
          y(unit(random), unit(random), unit(random));
      Vec3 n;
      const double d = signedDistance(shape, x, n);
      EXPECT_NEAR(n.norm(), 1.0, 1e-12) << config.name;
      EXPECT_LE(std::abs(d - signedDistance(shape, y)), (x - y).norm() + 1e-12) << config.name;
      EXPECT_NEAR(signedDistance(shape, x - d * n), 0.0, 1e-12) << config.name;
    }
  }
}

// The world bounds hold every surface point, for turned shapes too.
TEST(CollisionShapes, WorldBoundsHoldTheShape) {
  const Eigen::Quaterniond turn(Eigen::AngleAxisd(1.1, Vec3(-1.0, 0.5, 2.0).normalized()));
  const Pose pose = test::makePose(Vec3(0.3, -2.0, 1.0), turn);
  const ObstacleConfig configs[] = {test::sphere("s", 0.3, pose),
                                    test::box("b", Vec3(0.4, 0.2, 0.6), pose),
                                    test::capsule("c", 0.1, 0.5, pose)};
  std::mt19937 random(5);
  std::uniform_real_distribution<double> unit(-1.0, 1.0);
  for (const ObstacleConfig& config : configs) {
    const Shape shape = shapeOf(config);
    const Frame frame = frameFromPose(pose);
    Vec3 lo, hi;
    worldBounds(shape, frame, lo, hi);
    for (int k = 0; k < 2000; ++k) {
      Vec3 x(unit(random), unit(random), unit(random)), n;
      const double d = signedDistance(shape, x, n);
      const Vec3 surface = frame.toWorld(x - d * n);
      EXPECT_TRUE((surface.array() >= lo.array() - 1e-12).all() &&
                  (surface.array() <= hi.array() + 1e-12).all())
          << config.name;
    }
  }
}

// A plane's solid is bounded on the axis its normal lies along (a floor: from above), so the
// obstacles' cull can skip it; every point of the solid stays inside the bounds, and a tilted
// plane is unbounded on every axis.
TEST(CollisionShapes, WorldBoundsOfAPlaneEndAtItOnItsNormalsAxis) {
  std::mt19937 random(7);
  std::uniform_real_distribution<double> unit(-2.0, 2.0);
  struct Case {
    Vec3 normal;
    double offset;
    Pose pose;
    int axis;  // the bounded axis, -1 for none
    double end;
  };
  const Eigen::Quaterniond tilt(Eigen::AngleAxisd(0.3, Vec3::UnitX()));
  const Case cases[] = {// z <= 0.4 / 2 + 0.1
                        {Vec3(0.0, 0.0, 2.0), 0.4, test::makePose(Vec3(5.0, -1.0, 0.1)), 2, 0.3},
                        // -y <= 0.5 - 0.25, so y >= -0.25
                        {Vec3(0.0, -1.0, 0.0), 0.5, test::makePose(Vec3(0.0, 0.25, 0.0)), 1, -0.25},
                        {Vec3(0.0, 0.0, 1.0), 0.0, test::makePose(Vec3::Zero(), tilt), -1, 0.0}};
  for (const Case& c : cases) {
    ObstacleConfig placed = test::plane("p", c.normal, c.offset);
    placed.pose = c.pose;
    const Shape shape = shapeOf(placed);
    const Frame frame = frameFromPose(c.pose);
    Vec3 lo, hi;
    worldBounds(shape, frame, lo, hi);
    for (int a = 0; a < 3; ++a) {
      if (a != c.axis) {
        EXPECT_EQ(lo[a], -std::numeric_limits<double>::infinity()) << "axis " << a;
        EXPECT_EQ(hi[a], std::numeric_limits<double>::infinity()) << "axis " << a;
      } else if (c.normal[a] > 0.0) {
        EXPECT_NEAR(hi[a], c.end, 1e-9);
        EXPECT_EQ(lo[a], -std::numeric_limits<double>::infinity());
      } else {
        EXPECT_NEAR(lo[a], c.end, 1e-9);
        EXPECT_EQ(hi[a], std::numeric_limits<double>::infinity());
      }
    }
    int inside = 0;
    for (int k = 0; k < 2000; ++k) {
      const Vec3 x(unit(random), unit(random), unit(random));
      if (signedDistance(shape, frame.toLocal(x)) > 0.0) continue;
      ++inside;
      EXPECT_TRUE((x.array() >= lo.array()).all() && (x.array() <= hi.array()).all())
          << x.transpose();
    }
    EXPECT_GT(inside, 200);  // the test sampled the solid
  }
}

// The swept sphere finds the entry into a plate it would jump over, and nothing on a clear path.
TEST(CollisionShapes, SweepCatchesAThinPlate) {
  const Shape plate = shapeOf(test::box("b", Vec3(1.0, 1.0, 0.002), test::makePose(Vec3::Zero())));
  const Vec3 a(0.1, 0.0, 0.05), b(0.1, 0.0, -0.05);
  Vec3 na, n;
  const double start = signedDistance(plate, a, na);
  double t = 0.0;
  ASSERT_TRUE(sweepSphere(plate, a, b, 0.01, start, na, t, n));
  EXPECT_NEAR(t, (0.05 - 0.011) / 0.1, 1e-9);  // centre r + h/2 above the mid-plane
  EXPECT_TRUE(n.isApprox(Vec3::UnitZ()));
  const Vec3 c(0.7, 0.0, -0.05);  // passes beside the plate's edge at x = 0.5
  const Vec3 d(0.7, 0.0, 0.05);
  EXPECT_FALSE(sweepSphere(plate, c, d, 0.01, signedDistance(plate, c, na), na, t, n));
}

// The hash reports exactly the overlapping boxes, each once, whatever the box sizes (a few long
// boxes, like fast particles, among small ones).
TEST(CollisionBroadPhase, SpatialHashMatchesBruteForce) {
  std::mt19937 random(11);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  const int count = 500;
  Vec3Array lo(count), hi(count);
  for (int k = 0; k < count; ++k) {
    lo[k] = Vec3(unit(random), unit(random), unit(random));
    const double size = k % 50 == 0 ? 0.5 : 0.03 * unit(random);
    hi[k] = lo[k] + size * Vec3(unit(random), unit(random), unit(random));
  }
  SpatialHash hash;
  hash.reserve(count);
  hash.build(lo, hi, count, 0.03);
  for (int q = 0; q < 200; ++q) {
    const Vec3 q_lo(unit(random), unit(random), unit(random));
    const Vec3 q_hi = q_lo + 0.05 * Vec3(unit(random), unit(random), unit(random));
    std::multiset<int> found;
    hash.forEachOverlapping(q_lo, q_hi, [&](int k) { found.insert(k); });
    std::multiset<int> expected;
    for (int k = 0; k < count; ++k) {
      if ((q_lo.array() <= hi[k].array()).all() && (lo[k].array() <= q_hi.array()).all()) {
        expected.insert(k);
      }
    }
    EXPECT_EQ(found, expected) << "query " << q;
  }
}

// Case 13: a particle of radius r flying at a plate of thickness h with v dt / (2 r + h) from 0.5
// to 4 (one substep, so a discrete test would jump it): it must never reach the far side, and
// comes to rest on the near face. Head-on and oblique, at several phases of where the steps fall.
TEST(CollisionTunnelling, ParticleNeverPassesAThinPlate) {
  const double r = 0.01, plate = 0.002, dt = 1.0 / 60.0;
  int runs = 0;
  for (double ratio = 0.5; ratio <= 4.0 + 1e-9; ratio += 0.25) {
    for (double phase : {0.0, 0.13, 0.37, 0.71, 0.93}) {
      for (double slant : {0.0, 1.0}) {
        const double v = ratio * (2.0 * r + plate) / dt;
        SceneConfig scene = test::pointParticleScene(r, Vec3(0.0, 0.0, 0.1 + phase * v * dt));
        scene.solver.gravity.setZero();
        scene.cloth.friction = FrictionConfig{0.0, 0.0};
        scene.obstacles = {
            test::box("plate", Vec3(10.0, 10.0, plate), test::makePose(Vec3::Zero()))};
        Simulation sim(scene);
        sim.mutableParticles().velocity[kPoint] = Vec3(slant * v, 0.0, -v);
        for (int k = 0; k < 40; ++k) {
          sim.step();
          ASSERT_GT(sim.particles().position[kPoint].z(), 0.0)
              << "passed at ratio " << ratio << ", phase " << phase << ", slant " << slant;
        }
        EXPECT_NEAR(sim.particles().position[kPoint].z(), r + 0.5 * plate, 1e-9);
        ++runs;
      }
    }
  }
  EXPECT_EQ(runs, 15 * 5 * 2);
}

// The same against a turned plate and a thin rod, and a plate that moves through a resting
// particle at 5 m/s (30 times the gap per step): the particle ends on the side it started on.
TEST(CollisionTunnelling, TurnedPlateThinRodAndMovingPlate) {
  const double r = 0.01, dt = 1.0 / 60.0;
  const Eigen::Quaterniond tilt(Eigen::AngleAxisd(0.5, Vec3::UnitX()));
  const Vec3 normal = tilt * Vec3::UnitZ();
  {
    SceneConfig scene = test::pointParticleScene(r, 0.2 * normal);
    scene.solver.gravity.setZero();
    scene.obstacles = {
        test::box("plate", Vec3(2.0, 2.0, 0.001), test::makePose(Vec3::Zero(), tilt))};
    Simulation sim(scene);
    sim.mutableParticles().velocity[kPoint] = -3.0 * 0.021 / dt * normal;
    for (int k = 0; k < 30; ++k) {
      sim.step();
      ASSERT_GT(sim.particles().position[kPoint].dot(normal), 0.0) << "turned plate, step " << k;
    }
  }
  {
    // A rod of 1 mm radius along y, hit across at 4 x (2 r + 2 mm) per step.
    const Eigen::Quaterniond along_y(Eigen::AngleAxisd(test::kPiValue / 2.0, Vec3::UnitX()));
    SceneConfig scene = test::pointParticleScene(r, Vec3(0.0, 0.0, 0.1));
    scene.solver.gravity.setZero();
    scene.obstacles = {test::capsule("rod", 0.001, 1.0, test::makePose(Vec3::Zero(), along_y))};
    Simulation sim(scene);
    sim.mutableParticles().velocity[kPoint] = Vec3(0.0, 0.0, -4.0 * 0.022 / dt);
    for (int k = 0; k < 30; ++k) {
      sim.step();
      ASSERT_GT(sim.particles().position[kPoint].z(), 0.0) << "rod, step " << k;
    }
  }
  {
    SceneConfig scene = test::pointParticleScene(r, Vec3(0.0, 0.0, 0.0));
    scene.solver.gravity.setZero();
    scene.obstacles = {test::box("plate", Vec3(1.0, 1.0, 0.002), test::makePose(Vec3(0, 0, -0.2)))};
    Simulation sim(scene);
    for (int k = 1; k <= 30; ++k) {
      sim.setObstaclePose(0, test::makePose(Vec3(0.0, 0.0, -0.2 + 5.0 * k * dt)));
      sim.step();
    }
    // The plate is at z = 2.3 m now, carrying the particle on top.
    EXPECT_NEAR(sim.particles().position[kPoint].z(), -0.2 + 5.0 * 30 * dt + 0.001 + r, 1e-9);
  }
}

// A ball sweeping through a hanging curtain pushes it along, at walking speed and at 20 m/s
// (a third of a metre per step): no particle is ever inside the ball.
TEST(CollisionMovingObstacle, SphereSweepsThroughCurtainAndNoParticleEndsInside) {
  for (double speed : {1.0, 20.0}) {
    SceneConfig scene = test::clothScene(16, 16, 0.02, Method::kXpbd);
    scene.solver.substeps = 10;
    scene.cloth.thickness = 0.004;
    scene.cloth.bend_compliance = 1.0;
    scene.cloth.rpy = Vec3(test::kPiValue / 2.0, 0.0, 0.0);  // hangs in the x-z plane
    scene.cloth.origin = Vec3(-0.15, 0.0, 0.3);
    scene.cloth.pinned = {0, 15};
    scene.obstacles = {test::sphere("ball", 0.06, test::makePose(Vec3(0.0, -0.3, 0.15)))};
    Simulation sim(scene);
    const double dt = 1.0 / scene.step_rate;
    const int middle = 8 * 16 + 8;
    double y = -0.3, worst = 0.0, pushed = 0.0;
    for (int k = 0; k < 150; ++k) {
      y = std::min(0.1, y + speed * dt);
      sim.setObstaclePose(0, test::makePose(Vec3(0.0, y, 0.15)));
      sim.step();
      worst = std::max(worst, test::obstaclePenetration(sim));
      pushed = std::max(pushed, sim.particles().position[middle].y());
    }
    std::printf(
        "ball at %.0f m/s: deepest particle %.2e m, middle of curtain pushed to y = %.3f m\n",
        speed, worst, pushed);
    EXPECT_LT(worst, 0.01 * 0.004) << speed << " m/s";
    // The middle of the curtain was carried at least to the front of the ball's final place
    // (y = 0.1 + 0.06 + thickness), less the bit it slides round the ball's side.
    EXPECT_GT(pushed, 0.1 + 0.06 - 0.01) << speed << " m/s";
    EXPECT_TRUE(sim.computeMetrics().finite);
  }
}

// The obstacles' first pass culls particles in blocks by the paths they had before it
// (collisions.cpp, kCullBlock). A particle that one obstacle pushes off its path must still meet
// the obstacles after it: a ball sweeping 0.15 m in one substep into a resting particle pushes it
// 6 cm, into a wall its own (still) path was 3 cm from, and the wall, listed after the ball,
// takes it out to its face (the ball then overlaps it: squeezed, the last contact wins).
TEST(CollisionCulling, AParticlePushedIntoALaterObstacleMeetsIt) {
  const double r = 0.01;
  SceneConfig scene = test::pointParticleScene(r, Vec3::Zero());
  scene.solver.gravity.setZero();
  scene.solver.substeps = 1;
  scene.cloth.friction = FrictionConfig{0.0, 0.0};
  scene.obstacles = {test::sphere("ball", 0.1, test::makePose(Vec3(0.2, 0.0, 0.0))),
                     test::box("wall", Vec3(0.26, 1.0, 1.0),
                               test::makePose(Vec3(-0.17, 0.0, 0.0)))};  // x <= -0.04
  Simulation sim(scene);
  sim.setObstaclePose(0, test::makePose(Vec3(0.05, 0.0, 0.0)));
  sim.step();
  EXPECT_NEAR(sim.particles().position[kPoint].x(), -0.04 + r, 1e-12)
      << "-0.06 would be the ball's push alone, inside the wall";
}

// The first pass leaves the bounds' clamp out for a particle whose path box lies inside the
// bounds (collisions.cpp, projectBlockFirstPass), which holds only while no contact has moved it.
// Pushed: the ball sweeps the resting particle 6 cm along -x, past the bounds' face at x = -0.04
// that its own path kept 3 cm inside of, and the clamp takes it back to that face. Unpushed: a
// particle flying out through the face is clamped to it too. A second obstacle, far away, puts
// the pass on its blocks (a single obstacle is culled particle by particle).
TEST(CollisionCulling, AParticleLeavingTheBoundsIsClampedWhateverMovedIt) {
  const double r = 0.01;
  for (const bool pushed : {true, false}) {
    SceneConfig scene = test::pointParticleScene(r, Vec3::Zero());
    scene.solver.gravity.setZero();
    scene.solver.substeps = 1;
    scene.cloth.friction = FrictionConfig{0.0, 0.0};
    scene.bounds.enabled = true;
    scene.bounds.min = Vec3(-0.04, -1.0, -1.0);
    scene.bounds.max = Vec3(200.0, 200.0, 200.0);  // the pinned pair at 100 m inside too
    scene.obstacles = {test::sphere("ball", 0.1, test::makePose(Vec3(0.2, 0.0, 0.0))),
                       test::box("far", Vec3(0.1, 0.1, 0.1), test::makePose(Vec3(0.0, 0.0, 5.0)))};
    Simulation sim(scene);
    if (pushed) {
      sim.setObstaclePose(0, test::makePose(Vec3(0.05, 0.0, 0.0)));
    } else {
      sim.mutableParticles().velocity[kPoint] = Vec3(-0.06 * scene.step_rate, 0.0, 0.0);
    }
    sim.step();
    EXPECT_NEAR(sim.particles().position[kPoint].x(), -0.04, 1e-12)
        << (pushed ? "pushed by the ball" : "flying out") << ": -0.06 without the clamp";
  }
}

// The shipped drape scene (config/drape.yaml): a cloth dropped onto a ball on a table. Contact
// penetration below 10 % of the thickness at every step, no self-intersection, finite.
TEST(CollisionDrape, ShippedDrapeSceneStaysOutsideBallAndTable) {
  SceneConfig scene = loadScene(std::string(PBD_CLOTH_SOURCE_DIR) + "/config/drape.yaml");
  ASSERT_TRUE(scene.cloth.self_collision);
  Simulation sim(scene);
  const double thickness = scene.cloth.thickness;
  double worst = 0.0, worst_obstacle = 0.0;
  for (int k = 0; k < 150; ++k) {
    sim.step();
    worst = std::max(worst, sim.stats().max_penetration);
    worst_obstacle = std::max(worst_obstacle, test::obstaclePenetration(sim));
    if (k % 10 == 9) {
      ASSERT_EQ(countSelfIntersections(sim.particles(), sim.topology()), 0) << "step " << k;
    }
  }
  std::printf("drape: max penetration %.2e m (obstacles %.2e m), thickness %.3f m\n", worst,
              worst_obstacle, thickness);
  EXPECT_LT(worst, 0.1 * thickness);
  EXPECT_TRUE(sim.computeMetrics().finite);
  // It drapes: particles rest on the ball (at its radius plus the thickness from its centre), the
  // corners hang below the ball's equator.
  const Particles& p = sim.particles();
  double closest = 1.0;
  for (int i = 0; i < p.size(); ++i) {
    closest = std::min(closest, (p.position[i] - Vec3(0.0, 0.0, 0.5)).norm());
  }
  EXPECT_NEAR(closest, 0.2 + thickness, 1e-4);
  for (int corner : {0, 31, 992, 1023}) EXPECT_LT(p.position[corner].z(), 0.5);
}

// The same drape with stiff XPBD bending (compliance 1 and 1e-4 instead of the scene's 30), 3 s at
// the scene's 20 substeps. Stiff bending is where the free edges whip: with the constraints swept
// in the builder's earlier order (commit f90b61a) these runs reached 2.9 and 4.3 cm of
// self-collision penetration; the sweep in runs of independent constraints keeps it at 0.
TEST(CollisionDrape, StiffBendingDrapesWithoutPenetration) {
  for (double compliance : {1.0, 1e-4}) {
    SceneConfig scene = loadScene(std::string(PBD_CLOTH_SOURCE_DIR) + "/config/drape.yaml");
    scene.cloth.bend_compliance = compliance;
    Simulation sim(scene);
    const double thickness = scene.cloth.thickness;
    double worst = 0.0;
    int intersections = 0;
    for (int k = 0; k < 180; ++k) {
      sim.step();
      worst = std::max(worst, sim.stats().max_penetration);
      if (k % 10 == 9) {
        intersections =
            std::max(intersections, countSelfIntersections(sim.particles(), sim.topology()));
      }
    }
    std::printf("drape, bend compliance %g: max penetration %.2e m, max self-intersections %d\n",
                compliance, worst, intersections);
    EXPECT_LT(worst, 0.1 * thickness) << "bend compliance " << compliance;
    EXPECT_EQ(intersections, 0) << "bend compliance " << compliance;
    EXPECT_TRUE(sim.computeMetrics().finite);
  }
}

// A cloth spawned half inside a box is pushed out over a few steps without gaining speed
// (pre-stabilisation), and ends resting on top.
TEST(CollisionInitialOverlap, ClothStartingInsideBoxLeavesWithoutPopping) {
  SceneConfig scene = test::clothScene(8, 8, 0.02, Method::kXpbd);
  scene.solver.substeps = 10;
  scene.cloth.thickness = 0.005;
  scene.cloth.origin = Vec3(-0.07, 0.07, -0.02);  // 2 cm deep inside the box's top
  scene.obstacles = {test::box("block", Vec3(0.5, 0.5, 0.2), test::makePose(Vec3(0, 0, -0.1)))};
  Simulation sim(scene);
  EXPECT_GT(sim.computeMetrics().max_penetration, 0.02);
  // Not silent: one start-up warning names the obstacle, how many particles and the first.
  ASSERT_EQ(sim.startWarnings().size(), 1u);
  EXPECT_NE(sim.startWarnings()[0].find("64 particle(s) start more than 1 mm inside obstacle "
                                        "'block' (first: particle 0)"),
            std::string::npos)
      << sim.startWarnings()[0];
  double max_speed = 0.0;
  for (int k = 0; k < 60; ++k) {
    sim.step();
    for (const Vec3& v : sim.particles().velocity) max_speed = std::max(max_speed, v.norm());
  }
  std::printf("cloth inside box: max speed %.3e m/s, final penetration %.2e m\n", max_speed,
              sim.stats().max_penetration);
  EXPECT_LT(sim.stats().max_penetration, 1e-9);
  // Resolving 2.5 cm by projection within one substep would fling it at ~15 m/s.
  EXPECT_LT(max_speed, 0.2);
  for (const Vec3& x : sim.particles().position) EXPECT_NEAR(x.z(), 0.005, 1e-6);
}

// A cloth resting on the box within its thickness is no overlap (a mesh cloth that starts
// self-intersecting: ClothMesh.SelfIntersectingStartIsWarnedAbout).
TEST(CollisionInitialOverlap, RestingOnABoxIsNoOverlap) {
  SceneConfig scene = test::clothScene(8, 8, 0.02, Method::kXpbd);
  scene.cloth.thickness = 0.005;
  scene.cloth.origin = Vec3(-0.07, 0.07, 0.005);
  scene.obstacles = {test::box("block", Vec3(0.5, 0.5, 0.2), test::makePose(Vec3(0, 0, -0.1)))};
  EXPECT_TRUE(Simulation(scene).startWarnings().empty());
}

}  // namespace
}  // namespace pbd_cloth
