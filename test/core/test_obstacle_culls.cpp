// The obstacle contact pass's culls (path_boxes.h; shapes.h surelyFartherThan, boundingRadius):
// the path boxes' AVX-512VL, AVX2 and portable kernels agree to the bit, NaN and kinematic
// particles included, and give the boxes their definition says; the distance pre-test never
// answers "farther" where the contact pass's own test would not skip, and does answer it away
// from the shapes; every shape lies within its bounding ball.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <limits>
#include <random>
#include <vector>

#include "mesh_builders.h"
#include "pbd_cloth/collision/path_boxes.h"
#include "pbd_cloth/geometry/shapes.h"
#include "pbd_cloth/sim/simulation.h"
#include "test_scenes.h"

namespace pbd_cloth {
namespace {

Particles randomParticles(int n, std::mt19937& rng) {
  std::uniform_real_distribution<double> coordinate(-2.0, 2.0), step(-0.01, 0.01),
      radius(0.001, 0.01);
  Particles p;
  p.resize(n);
  for (int i = 0; i < n; ++i) {
    p.position[i] = Vec3(coordinate(rng), coordinate(rng), coordinate(rng));
    p.substep_start[i] = p.position[i] + Vec3(step(rng), step(rng), step(rng));
    p.radius[i] = radius(rng);
    p.mass[i] = 0.01;
    p.inverse_mass[i] = 100.0;
  }
  return p;
}

bool sameBits(double a, double b) { return std::memcmp(&a, &b, sizeof a) == 0; }

// Every kernel this processor runs, on blocks of 32 with kinematic particles, signed zeros, a
// NaN in x, in the start and in both (the last particle of the array among them, whose next
// double the masked load must not read: the arrays end there): boxes, union and the "not a box"
// flag the same bits as the portable loop's.
TEST(PathBoxes, KernelsAgreeToTheBit) {
  std::mt19937 rng(7);
  const int n = 96;
  Particles p = randomParticles(n, rng);
  const double nan = std::numeric_limits<double>::quiet_NaN();
  p.inverse_mass[3] = p.inverse_mass[40] = 0.0;  // kinematic: skipped
  p.position[5] = Vec3(0.0, -0.0, 0.0);          // signed zeros
  p.substep_start[5] = Vec3(-0.0, 0.0, -0.0);
  p.position[50].y() = nan;       // second block: NaN at the end
  p.substep_start[70].z() = nan;  // third block: NaN at the start only
  p.position[n - 1].x() = nan;    // the array's last particle
  p.substep_start[n - 1].x() = nan;
  std::vector<PathBoxKernel> kernels = {PathBoxKernel::kPortable};
  if (bestPathBoxKernel(true, false) == PathBoxKernel::kAvx2)
    kernels.push_back(PathBoxKernel::kAvx2);
  if (bestPathBoxKernel(true, true) == PathBoxKernel::kAvx512Vl) {
    kernels.push_back(PathBoxKernel::kAvx512Vl);
  }
  EXPECT_EQ(bestPathBoxKernel(false, true), PathBoxKernel::kPortable);
  for (int begin = 0; begin < n; begin += 32) {
    PathBox expected[32];
    Eigen::Array3d expected_lo, expected_hi;
    const bool expected_every = computePathBoxes(PathBoxKernel::kPortable, p, begin, begin + 32,
                                                 expected, expected_lo, expected_hi);
    EXPECT_EQ(expected_every, begin >= 32) << "block " << begin;
    for (PathBoxKernel kernel : kernels) {
      PathBox box[32];
      Eigen::Array3d lo, hi;
      const bool every = computePathBoxes(kernel, p, begin, begin + 32, box, lo, hi);
      EXPECT_EQ(every, expected_every) << "kernel " << static_cast<int>(kernel);
      for (int d = 0; d < 3; ++d) {
        EXPECT_TRUE(sameBits(lo[d], expected_lo[d])) << "kernel " << static_cast<int>(kernel);
        EXPECT_TRUE(sameBits(hi[d], expected_hi[d])) << "kernel " << static_cast<int>(kernel);
        for (int i = begin; i < begin + 32; ++i) {
          if (p.inverse_mass[i] == 0.0) continue;
          EXPECT_TRUE(sameBits(box[i - begin].lo[d], expected[i - begin].lo[d]))
              << "kernel " << static_cast<int>(kernel) << " particle " << i << " axis " << d;
          EXPECT_TRUE(sameBits(box[i - begin].hi[d], expected[i - begin].hi[d]))
              << "kernel " << static_cast<int>(kernel) << " particle " << i << " axis " << d;
        }
      }
    }
  }
}

// The boxes are what they are defined to be: min(start, x) - r and max(start, x) + r (x -/+ r
// with the positions as the start), the union holds every free particle's box and only those,
// and a block of kinematic particles has the empty union (+inf, -inf).
TEST(PathBoxes, BoxesHoldThePathsAndTheUnionTheBoxes) {
  Particles p;
  p.resize(3);
  p.position = {Vec3(1.0, 2.0, 3.0), Vec3(-1.0, 0.5, 0.0), Vec3(9.0, 9.0, 9.0)};
  p.substep_start = {Vec3(0.0, 5.0, 3.0), Vec3(-1.5, 0.25, 0.5), Vec3(9.0, 9.0, 9.0)};
  p.radius = {0.125, 0.25, 0.5};
  p.inverse_mass = {1.0, 1.0, 0.0};  // the third kinematic: not in the union
  for (PathBoxKernel kernel : {PathBoxKernel::kPortable, bestPathBoxKernel(true, true)}) {
    PathBox box[3];
    Eigen::Array3d lo, hi;
    EXPECT_FALSE(computePathBoxes(kernel, p, 0, 3, box, lo, hi));
    EXPECT_EQ(box[0].low().matrix(), Vec3(-0.125, 1.875, 2.875));
    EXPECT_EQ(box[0].high().matrix(), Vec3(1.125, 5.125, 3.125));
    EXPECT_EQ(box[1].low().matrix(), Vec3(-1.75, 0.0, -0.25));
    EXPECT_EQ(box[1].high().matrix(), Vec3(-0.75, 0.75, 0.75));
    EXPECT_EQ(lo.matrix(), Vec3(-1.75, 0.0, -0.25));
    EXPECT_EQ(hi.matrix(), Vec3(1.125, 5.125, 3.125));
    // From the positions themselves: each particle's sphere's box, x -/+ r.
    EXPECT_FALSE(computePathBoxes(kernel, p, p.position, 0, 3, box, lo, hi));
    EXPECT_EQ(box[0].low().matrix(), Vec3(0.875, 1.875, 2.875));
    EXPECT_EQ(box[1].high().matrix(), Vec3(-0.75, 0.75, 0.25));
    Eigen::Array3d none_lo, none_hi;
    EXPECT_FALSE(computePathBoxes(kernel, p, 2, 3, box, none_lo, none_hi));
    EXPECT_TRUE((none_lo == std::numeric_limits<double>::infinity()).all());
    EXPECT_TRUE((none_hi == -std::numeric_limits<double>::infinity()).all());
  }
}

// reachedObstacles: for each free particle, a bit for each obstacle box its path box shares a
// point with and whether it lies inside the bounds, the same from every kernel and the same as
// the boxes' definitions say (compared coordinate by coordinate here); a box with a NaN lies
// inside nothing; kinematic particles' slots are left alone.
TEST(PathBoxes, ReachedObstaclesAreThoseTheBoxesShareAPointWith) {
  std::mt19937 rng(3);
  const int n = 32;
  Particles p = randomParticles(n, rng);
  p.inverse_mass[9] = 0.0;
  p.position[17].z() = std::numeric_limits<double>::quiet_NaN();
  std::uniform_real_distribution<double> corner(-2.0, 1.0), size(1.0, 2.5);
  std::vector<PathBox> obstacle;
  for (int q = 0; q < 5; ++q) {
    const Vec3 lo(corner(rng), corner(rng), corner(rng));
    obstacle.push_back(boxOfBounds(lo, lo + Vec3(size(rng), size(rng), size(rng))));
  }
  const PathBox bounds = boxOfBounds(Vec3(-1.5, -1.5, -1.5), Vec3(1.5, 1.5, 1.5));
  std::vector<PathBoxKernel> kernels = {PathBoxKernel::kPortable};
  if (bestPathBoxKernel(true, true) != PathBoxKernel::kPortable) {
    kernels.push_back(bestPathBoxKernel(true, true));
  }
  int reached = 0, inside_count = 0;
  for (PathBoxKernel kernel : kernels) {
    PathBox box[n];
    Eigen::Array3d lo, hi;
    computePathBoxes(kernel, p, 0, n, box, lo, hi);
    std::uint64_t reach[n];
    unsigned char inside[n];
    reach[9] = 99;
    inside[9] = 7;
    reachedObstacles(kernel, p, 0, n, box, obstacle.data(), 5, bounds, reach, inside);
    EXPECT_EQ(reach[9], 99u);
    EXPECT_EQ(inside[9], 7);
    for (int i = 0; i < n; ++i) {
      if (i == 9) continue;
      const Eigen::Array3d l = box[i].low(), h = box[i].high();
      for (int q = 0; q < 5; ++q) {
        const Eigen::Array3d ol = obstacle[q].low(), oh = obstacle[q].high();
        const bool apart = (h < ol).any() || (l > oh).any();
        EXPECT_EQ((reach[i] >> q) & 1u, apart ? 0u : 1u)
            << "kernel " << static_cast<int>(kernel) << " particle " << i << " obstacle " << q;
        reached += !apart;
      }
      EXPECT_EQ(inside[i] != 0, (l >= bounds.low()).all() && (h <= bounds.high()).all())
          << "kernel " << static_cast<int>(kernel) << " particle " << i;
      inside_count += inside[i] != 0;
    }
    EXPECT_EQ(inside[17], 0);
  }
  // Both answers occur (else the comparison above would prove little).
  EXPECT_GT(reached, 10);
  EXPECT_LT(reached, 5 * 31 * static_cast<int>(kernels.size()));
  EXPECT_GT(inside_count, 5);
}

Shape testShape(ShapeType type) {
  Shape shape;
  shape.type = type;
  if (type == ShapeType::kMesh) {
    test::MeshGeometry torus = test::torusMesh(0.3, 0.1, 24, 12);
    for (Vec3& v : torus.vertices) v += Vec3(0.05, -0.02, 0.1);  // off its origin
    torus.orientOutward();
    shape.mesh = torus.build();
  }
  shape.radius = 0.2;
  shape.half_length = 0.3;
  shape.half_extents = Vec3(0.5, 0.4, 0.025);
  shape.padding = 0.001;
  return shape;
}

// Points around a sphere, a capsule and a box, many of them within rounding of the distance
// the test is asked about: wherever surelyFartherThan says true, the contact pass's own skip
// (Collisions::projectObstaclesOn: signedDistance - r >= path length) holds as computed; away
// from the shape it does say true (else it would save nothing), and never inside it.
TEST(SurelyFartherThan, NeverSaysFartherWhereTheDistanceDoesNot) {
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> unit(-1.0, 1.0), length(0.0, 0.02), r(0.001, 0.01);
  for (ShapeType type : {ShapeType::kSphere, ShapeType::kCapsule, ShapeType::kBox}) {
    const Shape shape = testShape(type);
    int farther = 0, near_boundary = 0;
    for (int trial = 0; trial < 20000; ++trial) {
      const Vec3 x(unit(rng), unit(rng), unit(rng));
      const double radius = r(rng), path = length(rng);
      // Half the points moved onto the sphere of distance radius + path around the shape,
      // within a few units in the last place: where rounding decides.
      Vec3 point = x;
      Vec3 normal;
      const double d = signedDistance(shape, x, normal);
      if (trial % 2 == 0 && d > 0.0) {
        point = x + (radius + path - d) * normal;
        ++near_boundary;
      }
      const double clearance = signedDistance(shape, point) - radius;
      if (surelyFartherThan(shape, point, radius + path)) {
        ++farther;
        EXPECT_GE(clearance, path) << toString(type) << " trial " << trial;
      }
      if (signedDistance(shape, point) < 0.0) {
        EXPECT_FALSE(surelyFartherThan(shape, point, 0.0)) << toString(type) << " inside";
      }
    }
    EXPECT_GT(farther, 5000) << toString(type);
    EXPECT_GT(near_boundary, 2000) << toString(type);
    EXPECT_TRUE(surelyFartherThan(shape, Vec3(3.0, 0.0, 0.0), 0.01)) << toString(type);
    EXPECT_FALSE(surelyFartherThan(shape, Vec3(0.0, 0.0, 0.0), 0.0)) << toString(type);
  }
  // No cheap test for the others: the caller computes their distance.
  EXPECT_FALSE(surelyFartherThan(testShape(ShapeType::kPlane), Vec3(0.0, 0.0, 5.0), 0.01));
  EXPECT_FALSE(surelyFartherThan(testShape(ShapeType::kCylinder), Vec3(5.0, 0.0, 0.0), 0.01));
}

// The distance to a shape is at least the distance to a ball holding it: for random points
// around each shape (the mesh a torus off its origin), signedDistance(x) >= |x| - boundingRadius,
// and points inside the shape lie in the ball; for the sphere, the capsule and the box the
// padded surface reaches the ball (the bound is tight). A plane has none.
TEST(BoundingRadius, HoldsEveryShapeAndBoundsItsDistance) {
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> unit(-0.8, 0.8);
  for (ShapeType type : {ShapeType::kSphere, ShapeType::kCapsule, ShapeType::kBox,
                         ShapeType::kCylinder, ShapeType::kMesh}) {
    const Shape shape = testShape(type);
    const double bound = boundingRadius(shape);
    ASSERT_TRUE(std::isfinite(bound)) << toString(type);
    int inside = 0;
    double farthest_inside = 0.0;
    for (int trial = 0; trial < 20000; ++trial) {
      const Vec3 x(unit(rng), unit(rng), unit(rng));
      const double d = signedDistance(shape, x);
      EXPECT_GE(d, x.norm() - bound - 1e-12) << toString(type) << " trial " << trial;
      if (d <= 0.0) {
        ++inside;
        farthest_inside = std::max(farthest_inside, x.norm());
        EXPECT_LE(x.norm(), bound) << toString(type);
      }
    }
    EXPECT_GT(inside, 50) << toString(type);
    if (type == ShapeType::kSphere || type == ShapeType::kCapsule || type == ShapeType::kBox) {
      // Points along the farthest direction, on the surface: the bound is reached.
      Vec3 far_point = type == ShapeType::kSphere    ? Vec3(0.2, 0.0, 0.0)
                       : type == ShapeType::kCapsule ? Vec3(0.0, 0.0, 0.5)
                                                     : Vec3(shape.half_extents);
      EXPECT_NEAR(far_point.norm() + shape.padding, bound, 1e-12) << toString(type);
      // ... and the padded surface reaches it there.
      EXPECT_NEAR(signedDistance(shape, far_point.normalized() * bound), 0.0, 1e-12)
          << toString(type);
    }
  }
  EXPECT_TRUE(std::isinf(boundingRadius(testShape(ShapeType::kPlane))));
}

// A block of particles whose boxes reach more obstacles than reachedObstacles has bits for
// (kMostReachTests): a 4 x 8 cloth, one block of 32, drops 9 cm onto a floor of 80 slabs
// listed row by row, those under its first row from index 70 on. Every particle comes to rest on
// its slab (none falls through, as it would if the obstacles past the bits were not tested), at
// the slab's top plus its radius.
TEST(ObstacleCulls, ABlockNearMoreObstaclesThanTheBitsTestsThemAll) {
  SceneConfig scene = test::clothScene(4, 8, 0.06, Method::kXpbd);
  scene.solver.substeps = 10;
  scene.cloth.origin = Eigen::Vector3d(-0.21, 0.09, 0.1);
  scene.cloth.thickness = 0.004;
  for (int j = 0; j < 8; ++j) {
    for (int i = 0; i < 10; ++i) {
      ObstacleConfig slab;
      slab.name = "slab" + std::to_string(10 * j + i);
      slab.shape = ShapeType::kBox;
      slab.size = Eigen::Vector3d(0.05, 0.025, 0.02);
      slab.pose.position = Eigen::Vector3d(-0.225 + 0.05 * i, -0.0875 + 0.025 * j, 0.0);
      scene.obstacles.push_back(slab);
    }
  }
  ASSERT_GT(static_cast<int>(scene.obstacles.size()), kMostReachTests);
  Simulation sim(scene);
  const Particles& p = sim.particles();
  ASSERT_EQ(p.size(), 32);
  EXPECT_NEAR(p.position[0].y(), 0.09, 1e-12);  // the first row over slabs 70 to 79
  for (int step = 0; step < 60; ++step) sim.step();
  for (int i = 0; i < p.size(); ++i) {
    EXPECT_NEAR(p.position[i].z(), 0.01 + p.radius[i], 0.2 * p.radius[i]) << "particle " << i;
  }
}

}  // namespace
}  // namespace pbd_cloth
