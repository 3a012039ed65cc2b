// Cylinder and mesh shapes (issue 10): the mesh's signed distance against analytic answers, the
// cavity and the hole a convex hull would fill, and the continuous sweep of a thin moving plate.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <random>

#include "collision_scenes.h"
#include "mesh_builders.h"
#include "pbd_cloth/geometry/shapes.h"
#include "pbd_cloth/sim/simulation.h"

namespace pbd_cloth {
namespace {

using test::makePose;

// Points in a cube around the origin, reproducible.
std::vector<Vec3> samplePoints(double half, int count, unsigned seed) {
  std::mt19937 random(seed);
  std::uniform_real_distribution<double> coordinate(-half, half);
  std::vector<Vec3> points;
  for (int k = 0; k < count; ++k) {
    points.emplace_back(coordinate(random), coordinate(random), coordinate(random));
  }
  return points;
}

TEST(MeshShape, BoxMeshEqualsTheBoxExactly) {
  // A box is its own 12-triangle mesh: the distance and normal must agree to rounding, inside
  // (through the nearest face) and outside (face, edge and corner regions).
  const Vec3 half(0.3, 0.2, 0.1);
  ObstacleConfig box_config = test::box("box", 2.0 * half, Pose());
  const Shape box = makeShape(box_config);
  const Shape mesh = makeShape(test::meshObstacle("mesh", test::boxMesh(half), Pose()));
  double worst = 0.0, worst_normal = 0.0;
  for (const Vec3& x : samplePoints(0.6, 20000, 1)) {
    Vec3 n_box, n_mesh;
    const double d_box = signedDistance(box, x, n_box);
    const double d_mesh = signedDistance(mesh, x, n_mesh);
    worst = std::max(worst, std::abs(d_box - d_mesh));
    // Inside, points equally near two faces may pick either: compare normals away from ties.
    Vec3 q = x.cwiseAbs() - half;
    std::sort(q.data(), q.data() + 3);
    if (d_box > 1e-9 || q[2] - q[1] > 1e-6) {
      worst_normal = std::max(worst_normal, (n_box - n_mesh).norm());
    }
  }
  std::printf(
      "[ measured ] box mesh against the box: |d error| <= %.3g m, |normal error| <= %.3g\n", worst,
      worst_normal);
  EXPECT_LT(worst, 1e-12);
  EXPECT_LT(worst_normal, 1e-9);
}

TEST(MeshShape, SphereMeshWithinItsChordalErrorOfTheSphere) {
  // An icosphere (level 3, 1280 triangles) lies between its inscribed sphere and the sphere: the
  // distance error is at most R - r_in, the sign is right wherever the point is farther than that.
  const double radius = 0.1;
  const test::MeshGeometry geometry = test::icosphere(radius, 3);
  double inradius = radius;
  for (const auto& t : geometry.triangles) {
    const Vec3 &a = geometry.vertices[t[0]], &b = geometry.vertices[t[1]],
               &c = geometry.vertices[t[2]];
    inradius = std::min(inradius, std::abs((b - a).cross(c - a).normalized().dot(a)));
  }
  const double bound = radius - inradius;
  const Shape sphere = makeShape(test::sphere("sphere", radius, Pose()));
  const Shape mesh = makeShape(test::meshObstacle("mesh", geometry, Pose()));
  double worst = 0.0;
  int wrong_sign = 0;
  for (const Vec3& x : samplePoints(0.25, 20000, 2)) {
    const double d_sphere = signedDistance(sphere, x);
    const double d_mesh = signedDistance(mesh, x);
    worst = std::max(worst, std::abs(d_sphere - d_mesh));
    if (std::abs(d_sphere) > bound && (d_sphere > 0.0) != (d_mesh > 0.0)) ++wrong_sign;
  }
  std::printf(
      "[ measured ] icosphere (%zu triangles, R = %.2f m) against the sphere: |d error| <= "
      "%.3g m (bound R - r_in = %.3g m)\n",
      geometry.triangles.size(), radius, worst, bound);
  EXPECT_LE(worst, bound + 1e-12);
  EXPECT_EQ(wrong_sign, 0);
}

TEST(MeshShape, DistanceIsOneLipschitzAndKeepsTheMugCavity) {
  // The mug's cavity is outside the solid: the signed distance there is positive (a convex hull
  // would make it negative), and the distance never changes faster than the point moves.
  const test::MeshGeometry mug = test::mugMesh(0.04, 0.1, 0.005, 0.01, 48);
  const Shape shape = makeShape(test::meshObstacle("mug", mug, Pose()));
  EXPECT_GT(signedDistance(shape, Vec3(0.0, 0.0, 0.05)), 0.02);    // the middle of the cavity
  EXPECT_LT(signedDistance(shape, Vec3(0.0375, 0.0, 0.05)), 0.0);  // inside the wall
  EXPECT_LT(signedDistance(shape, Vec3(0.0, 0.0, 0.005)), 0.0);    // inside the bottom
  const std::vector<Vec3> points = samplePoints(0.08, 4000, 3);
  for (std::size_t k = 1; k < points.size(); ++k) {
    const Vec3 a = points[k - 1] + Vec3(0, 0, 0.05), b = points[k] + Vec3(0, 0, 0.05);
    EXPECT_LE(std::abs(signedDistance(shape, a) - signedDistance(shape, b)),
              (a - b).norm() + 1e-12);
  }
}

TEST(MeshShape, OpenMeshIsATwoSidedShell) {
  test::MeshGeometry sheet;
  sheet.vertices = {{-1, -1, 0}, {1, -1, 0}, {1, 1, 0}, {-1, 1, 0}};
  sheet.triangles = {{0, 1, 2}, {0, 2, 3}};
  const auto mesh = sheet.build();
  EXPECT_FALSE(mesh->closed());
  EXPECT_EQ(mesh->boundaryEdges(), 4);
  Vec3 normal;
  EXPECT_NEAR(mesh->signedDistance(Vec3(0.2, 0.1, 0.3), normal), 0.3, 1e-15);
  EXPECT_NEAR(normal.z(), 1.0, 1e-15);
  EXPECT_NEAR(mesh->signedDistance(Vec3(0.2, 0.1, -0.3), normal), 0.3, 1e-15);
  EXPECT_NEAR(normal.z(), -1.0, 1e-15);
}

TEST(MeshShape, DegenerateAndBadTrianglesAreHandled) {
  test::MeshGeometry g = test::boxMesh(Vec3(0.1, 0.1, 0.1));
  g.triangles.push_back({0, 0, 1});  // repeated index
  g.vertices.push_back(g.vertices[0]);
  g.vertices.push_back(g.vertices[1]);
  g.triangles.push_back({0, 8, 1});  // a duplicated vertex: welded, then degenerate
  const TriangleMesh mesh(g.vertices, g.triangles);
  EXPECT_EQ(mesh.degenerateTriangles(), 2);
  EXPECT_EQ(mesh.triangleCount(), 12);
  EXPECT_EQ(mesh.vertexCount(), 8);
  EXPECT_TRUE(mesh.closed());
  EXPECT_THROW(TriangleMesh(g.vertices, {{0, 1, 99}}), std::invalid_argument);
  EXPECT_THROW(TriangleMesh(g.vertices, {{0, 0, 1}}), std::invalid_argument);
}

TEST(CylinderShape, FlatEndsAndSideAgainstAnalyticDistance) {
  ObstacleConfig config;
  config.name = "post";
  config.shape = ShapeType::kCylinder;
  config.radius = 0.1;
  config.length = 0.4;
  const Shape cylinder = makeShape(config);
  Vec3 n;
  EXPECT_NEAR(signedDistance(cylinder, Vec3(0.3, 0.0, 0.0), n), 0.2, 1e-15);  // side
  EXPECT_NEAR(n.x(), 1.0, 1e-15);
  EXPECT_NEAR(signedDistance(cylinder, Vec3(0.05, 0.0, 0.5), n), 0.3, 1e-15);  // flat end
  EXPECT_NEAR(n.z(), 1.0, 1e-15);
  // Beyond the rim: the distance to the circle edge, where a capsule would be rounder.
  EXPECT_NEAR(signedDistance(cylinder, Vec3(0.0, 0.13, -0.24), n), 0.05, 1e-15);
  EXPECT_NEAR(n.y(), 0.6, 1e-15);
  EXPECT_NEAR(n.z(), -0.8, 1e-15);
  EXPECT_NEAR(signedDistance(cylinder, Vec3(0.0, 0.0, 0.15), n), -0.05, 1e-15);  // nearer an end
  EXPECT_NEAR(n.z(), 1.0, 1e-15);
  EXPECT_NEAR(signedDistance(cylinder, Vec3(0.08, 0.0, 0.0), n), -0.02, 1e-15);  // nearer the side
  EXPECT_NEAR(n.x(), 1.0, 1e-15);
  config.padding = 0.01;
  EXPECT_NEAR(signedDistance(makeShape(config), Vec3(0.3, 0.0, 0.0)), 0.19, 1e-15);
}

// A hanging rope (spacing 1 cm) through the hole of a torus lying flat: the rope passes the hole's
// plane, where a convex hull would be solid.
TEST(MeshShape, RopeHangsThroughATorusHole) {
  SceneConfig scene = test::clothScene(40, 1, 0.01, Method::kXpbd);
  scene.solver.substeps = 10;
  scene.cloth.origin = Vec3(0.0, 0.0, 0.3);
  scene.cloth.rpy = Vec3(0.0, 0.0, 0.0);
  scene.cloth.mass = 0.04;
  scene.cloth.thickness = 0.004;
  scene.cloth.pinned = {0};
  // Rows run along -y from the origin: turn the rope so it hangs along -z.
  scene.cloth.rpy = Vec3(M_PI / 2.0, 0.0, 0.0);
  // Torus at z = 0.15 around the rope, hole radius 0.05 - 0.015 = 3.5 cm.
  const test::MeshGeometry torus = test::torusMesh(0.05, 0.015, 48, 16);
  scene.obstacles.push_back(test::meshObstacle("torus", torus, makePose(Vec3(0.005, 0.0, 0.15))));
  Simulation sim(scene);
  for (int k = 0; k < 120; ++k) sim.step();
  const Particles& p = sim.particles();
  // The free end hangs below the torus, every particle stays clear of the ring.
  EXPECT_LT(p.position[39].z(), 0.15 - 0.1);
  EXPECT_LE(sim.stats().max_penetration, 1e-6);
  for (int i = 0; i < 40; ++i) EXPECT_LT(std::hypot(p.position[i].x(), p.position[i].y()), 0.035);
}

// Granular particles dropped into a mug stay inside its cavity.
TEST(MeshShape, ParticlesInsideAMugStayInside) {
  SceneConfig scene = test::clothScene(1, 2, 0.1, Method::kXpbd);
  scene.cloth.origin = Vec3(100.0, 100.0, 100.0);
  scene.cloth.pinned = {0, 1};
  scene.solver.substeps = 10;
  scene.solver.iterations = 2;
  scene.granular.count = 8;
  scene.granular.radius = 0.006;
  scene.granular.mass = 0.002;
  scene.granular.region_min = Vec3(-0.015, -0.015, 0.03);
  scene.granular.region_max = Vec3(0.015, 0.015, 0.09);
  const double radius = 0.04, wall = 0.005, bottom = 0.01, height = 0.1;
  scene.obstacles.push_back(
      test::meshObstacle("mug", test::mugMesh(radius, height, wall, bottom, 48), Pose()));
  Simulation sim(scene);
  for (int k = 0; k < 180; ++k) {
    sim.step();
    const Particles& p = sim.particles();
    for (int i = p.cloth_count; i < p.size(); ++i) {
      // The cavity: within the inner wall, above the bottom (the 48-gon's inradius is within
      // 0.1 mm of the circle's).
      ASSERT_LT(std::hypot(p.position[i].x(), p.position[i].y()), radius - wall) << "step " << k;
      ASSERT_GT(p.position[i].z(), bottom) << "step " << k;
    }
  }
  EXPECT_LE(sim.stats().max_penetration, 0.01 * scene.granular.radius);
}

// A 1 cm thick mesh plate, face on, sweeps at 5 m/s into a cloth: no particle ever passes from in
// front of the plate to behind it within its face. Checked at the default substeps and at a single
// substep, when the plate moves 4 cm, four times its thickness, per step; on a cloth hanging from
// its top corners (which then slides off the plate's edges: the far side is reached around the
// plate, never through it) and on a free-floating one (no gravity: the plate carries it along).
void sweepPlateThroughCloth(int substeps, bool hanging) {
  SceneConfig scene = test::clothScene(20, 20, 0.02, Method::kXpbd);
  scene.step_rate = 120.0;
  scene.solver.substeps = substeps;
  if (!hanging) scene.solver.gravity = Vec3::Zero();
  if (hanging) scene.cloth.pinned = {0, 19};
  scene.cloth.mass = 0.1;
  scene.cloth.thickness = 0.003;
  scene.cloth.origin = Vec3(-0.19, 0.0, 1.0);
  scene.cloth.rpy = Vec3(M_PI / 2.0, 0.0, 0.0);  // in the x-z plane at y = 0
  const Vec3 half(0.1, 0.005, 0.1);              // 20 x 1 x 20 cm, thin along y (the motion)
  scene.obstacles.push_back(
      test::meshObstacle("plate", test::boxMesh(half), makePose(Vec3(0.0, -0.1, 0.8))));
  Simulation sim(scene);
  const double speed = 5.0, dt = 1.0 / scene.step_rate;
  // Within the face, 2 cm clear of its edges: a particle that slides around an edge in one step
  // (the hanging cloth is pulled over the plate's top edge by its pins) ends up behind the plate
  // without crossing it; that is not tunnelling.
  const double edge = 0.02;
  const auto in_face = [&](const Vec3& local) {
    return std::abs(local.x()) < half.x() - edge && std::abs(local.z()) < half.z() - edge;
  };
  std::vector<Vec3> before(sim.particles().cloth_count);
  int crossed = 0;
  for (int k = 1; k <= 30; ++k) {
    const Vec3 plate_before = sim.obstacle(0).pose.position;
    for (int i = 0; i < sim.particles().cloth_count; ++i) {
      before[i] = sim.particles().position[i] - plate_before;
    }
    sim.setObstaclePose(0, makePose(Vec3(0.0, -0.1 + speed * dt * k, 0.8)));
    sim.step();
    const Vec3 plate = sim.obstacle(0).pose.position;
    for (int i = 0; i < sim.particles().cloth_count; ++i) {
      const Vec3 now = sim.particles().position[i] - plate;
      if (before[i].y() > 0.0 && now.y() < 0.0 && in_face(before[i]) && in_face(now)) ++crossed;
    }
  }
  // The plate did carry the cloth along (1.25 m, the hanging one as far as its pins let it), and
  // nothing went through it.
  double mean_y = 0.0;
  for (int i = 0; i < sim.particles().cloth_count; ++i) mean_y += sim.particles().position[i].y();
  EXPECT_GT(mean_y / sim.particles().cloth_count, hanging ? 0.05 : 0.5) << "substeps " << substeps;
  EXPECT_EQ(crossed, 0) << "substeps " << substeps << (hanging ? ", hanging" : ", free");
  EXPECT_LE(sim.stats().max_penetration, 1e-6);
}

TEST(MeshShape, ThinPlateAtFiveMetresPerSecondLetsNothingThrough) {
  for (bool hanging : {true, false}) {
    sweepPlateThroughCloth(SceneConfig().solver.substeps, hanging);
    sweepPlateThroughCloth(1, hanging);
  }
}

}  // namespace
}  // namespace pbd_cloth
