// Simulated depth cameras (depth_camera.h) against analytic depth: a flat cloth lying on a table,
// a sphere (analytic and as a mesh), every primitive, the range limits, occlusion and the noise.
// Issue 11 asks for 1 mm at 1 m; the analytic primitives and the flat cloth are exact up to float
// rounding, so most tolerances here are far tighter and say why.
#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "mesh_builders.h"
#include "pbd_cloth/scene/scene_yaml.h"
#include "pbd_cloth/sensors/depth_camera.h"
#include "pbd_cloth/sim/simulation.h"
#include "test_scenes.h"

namespace pbd_cloth {
namespace {

// Float depth at ~1 m: one unit in the last place is 6e-8 m; the ray and plane arithmetic is in
// double. 1e-5 m leaves room and is still 100 times tighter than the issue's 1 mm.
constexpr double kFloatDepth = 1e-5;

// An optical frame at `position` looking straight down (optical z = world -z, x = world x,
// y = world -y): half a turn about x.
Frame lookingDown(const Vec3& position) {
  Frame frame;
  frame.rotation = Eigen::AngleAxisd(M_PI, Vec3::UnitX()).toRotationMatrix();
  frame.translation = position;
  return frame;
}

PinholeCamera camera320() {
  PinholeCamera camera;
  camera.width = 320;
  camera.height = 240;
  camera.fx = camera.fy = 277.0;
  camera.cx = 159.5;
  camera.cy = 119.5;
  camera.range_min = 0.1;
  camera.range_max = 5.0;
  return camera;
}

// The pixel whose ray passes nearest the world point p.
void pixelOf(const PinholeCamera& camera, const Frame& pose, const Vec3& p, int& u, int& v) {
  const Vec3 c = pose.toLocal(p);
  u = static_cast<int>(std::lround(camera.fx * c.x() / c.z() + camera.cx));
  v = static_cast<int>(std::lround(camera.fy * c.y() / c.z() + camera.cy));
}

struct Rendered {
  std::vector<float> depth;
  float at(const PinholeCamera& camera, int u, int v) const { return depth[v * camera.width + u]; }
};

Rendered render(const Simulation& sim, const PinholeCamera& camera, const Frame& pose) {
  DepthSnapshot snapshot;
  snapshot.capture(sim);
  DepthRenderer renderer;
  Rendered out;
  out.depth.resize(camera.pixelCount());
  renderer.render(snapshot, camera, pose, out.depth.data());
  return out;
}

ObstacleConfig obstacle(const std::string& name, ShapeType shape, const Vec3& position) {
  ObstacleConfig o;
  o.name = name;
  o.shape = shape;
  o.pose.position = position;
  return o;
}

// A scene of obstacles only: one particle far out of view (the solver needs one).
SceneConfig obstaclesOnly(std::vector<ObstacleConfig> obstacles) {
  SceneConfig scene = test::clothScene(1, 2, 1.0, Method::kXpbd);
  scene.cloth.origin = Vec3(100.0, 100.0, 100.0);
  scene.cloth.pinned = {0, 1};
  scene.obstacles = std::move(obstacles);
  return scene;
}

TEST(DepthCamera, FlatClothLyingOnATableHasTheAnalyticDepth) {
  // A 20 x 20 cloth (0.475 m) dropped 2 mm onto a 1 x 1 m table whose top is at z = 0.4, settled
  // for 1 s; the camera 1 m above the table top. The cloth rests at the top plus its thickness
  // (the particles' contact radius), so its analytic depth is 1 m - thickness.
  SceneConfig scene = test::clothScene(20, 20, 0.025, Method::kXpbd);
  scene.cloth.mass = 0.3;
  scene.cloth.thickness = 0.005;
  scene.solver.substeps = 10;
  scene.cloth.origin = Vec3(-0.2375, 0.2375, 0.4 + 0.005 + 0.002);
  ObstacleConfig table = obstacle("table", ShapeType::kBox, Vec3(0.0, 0.0, 0.375));
  table.size = Vec3(1.0, 1.0, 0.05);
  ObstacleConfig floor = obstacle("floor", ShapeType::kPlane, Vec3::Zero());
  floor.normal = Vec3::UnitZ();
  floor.offset = 0.0;
  scene.obstacles = {table, floor};
  Simulation sim(scene);
  for (int k = 0; k < 60; ++k) sim.step();

  const PinholeCamera camera = camera320();
  const Frame pose = lookingDown(Vec3(0.0, 0.0, 1.4));
  const Rendered image = render(sim, camera, pose);

  // Cloth: every pixel seeing the inner part of the square (one spacing in from its edges).
  const double cloth_depth = 1.0 - 0.005;
  int u0, v0, u1, v1;
  pixelOf(camera, pose, Vec3(-0.2125, 0.2125, 0.405), u0, v0);
  pixelOf(camera, pose, Vec3(0.2125, -0.2125, 0.405), u1, v1);
  ASSERT_LT(u0, u1);
  ASSERT_LT(v0, v1);
  double worst = 0.0;
  for (int v = v0; v <= v1; ++v) {
    for (int u = u0; u <= u1; ++u) {
      worst = std::max(worst, std::abs(image.at(camera, u, v) - cloth_depth));
    }
  }
  // 1 mm, the issue's figure: the resting cloth sits within a fraction of it of top + thickness.
  EXPECT_LT(worst, 1e-3) << "cloth pixels [" << u0 << ", " << u1 << "] x [" << v0 << ", " << v1
                         << "]";

  // Table top beside the cloth, and the floor beyond the table: exact.
  int ut, vt;
  pixelOf(camera, pose, Vec3(0.4, 0.0, 0.4), ut, vt);
  EXPECT_NEAR(image.at(camera, ut, vt), 1.0, kFloatDepth);
  int uf, vf;
  // At x = 0.78 the ray passes the table's top at x = 0.557, beyond its edge at 0.5.
  pixelOf(camera, pose, Vec3(0.78, 0.0, 0.0), uf, vf);
  EXPECT_NEAR(image.at(camera, uf, vf), 1.4, kFloatDepth);
}

// Depth along the optical axis of the first hit of the pixel's ray with a sphere, computed
// geometrically (closest approach of the unit ray), not by the renderer's quadratic.
double analyticSphereDepth(const PinholeCamera& camera, const Frame& pose, int u, int v,
                           const Vec3& centre, double radius) {
  const Vec3 w = camera.ray(u, v).normalized();  // camera frame
  const Vec3 c = pose.toLocal(centre);
  const double along = c.dot(w);
  const double miss2 = c.squaredNorm() - along * along;
  if (miss2 > radius * radius) return std::nan("");
  const double distance = along - std::sqrt(radius * radius - miss2);
  return distance * w.z();
}

TEST(DepthCamera, SphereAtOneMetreHasTheAnalyticDepthAndSilhouette) {
  ObstacleConfig ball = obstacle("ball", ShapeType::kSphere, Vec3(0.05, -0.03, 0.0));
  ball.radius = 0.2;
  const Simulation sim(obstaclesOnly({ball}));
  const PinholeCamera camera = camera320();
  const Frame pose = lookingDown(Vec3(0.0, 0.0, 1.2));  // the top of the ball 1 m away
  const Rendered image = render(sim, camera, pose);

  int seen = 0, expected = 0, silhouette_mismatches = 0;
  double worst = 0.0;
  for (int v = 0; v < camera.height; ++v) {
    for (int u = 0; u < camera.width; ++u) {
      const double truth = analyticSphereDepth(camera, pose, u, v, ball.pose.position, 0.2);
      const float got = image.at(camera, u, v);
      expected += std::isfinite(truth);
      seen += std::isfinite(got);
      if (std::isfinite(truth) != std::isfinite(got)) {
        ++silhouette_mismatches;
      } else if (std::isfinite(truth)) {
        worst = std::max(worst, std::abs(got - truth));
      }
    }
  }
  EXPECT_GT(expected, 5000);  // the ball covers a good part of the image
  EXPECT_EQ(silhouette_mismatches, 0) << seen << " seen, " << expected << " expected";
  EXPECT_LT(worst, kFloatDepth);
  int uc, vc;
  pixelOf(camera, pose, ball.pose.position, uc, vc);
  EXPECT_NEAR(image.at(camera, uc, vc), 1.0, 1e-3);
}

TEST(DepthCamera, MeshSphereIsWithinItsChordalErrorOfTheAnalyticSphere) {
  // The same ball as a 5120-triangle icosphere (vertices on the sphere): the depth is that of a
  // chord plane, radially at most r (1 - cos(circumradius angle)) ~ 0.16 mm inside the sphere at
  // r = 0.2, and along the ray that divided by the cosine of the view angle (> 0.43 within 0.9 r
  // of the silhouette's centre): under 0.4 mm, never in front of the sphere.
  const Vec3 centre(0.05, -0.03, 0.0);
  Pose at;
  at.position = centre;
  ObstacleConfig ball = test::meshObstacle("ball", test::icosphere(0.2, 4), at);
  const Simulation sim(obstaclesOnly({ball}));
  const PinholeCamera camera = camera320();
  const Frame pose = lookingDown(Vec3(0.0, 0.0, 1.2));
  const Rendered image = render(sim, camera, pose);
  double worst_behind = 0.0, worst_in_front = 0.0;
  int compared = 0;
  for (int v = 0; v < camera.height; ++v) {
    for (int u = 0; u < camera.width; ++u) {
      // Well inside the silhouette (0.9 r) the chords cannot miss.
      const double truth = analyticSphereDepth(camera, pose, u, v, centre, 0.2);
      const double inner = analyticSphereDepth(camera, pose, u, v, centre, 0.18);
      if (!std::isfinite(truth) || !std::isfinite(inner)) continue;
      const double error = image.at(camera, u, v) - truth;
      worst_behind = std::max(worst_behind, error);
      worst_in_front = std::max(worst_in_front, -error);
      ++compared;
    }
  }
  EXPECT_GT(compared, 5000);
  EXPECT_LT(worst_behind, 1e-3);
  EXPECT_LT(worst_in_front, kFloatDepth);
}

TEST(DepthCamera, EveryPrimitiveHasItsAnalyticDepthUnderTheCamera) {
  // One shape at a time under a camera 1.5 m above the floor; the centre pixel sees its top.
  ObstacleConfig box = obstacle("box", ShapeType::kBox, Vec3(0.0, 0.0, 0.3));
  box.size = Vec3(0.2, 0.3, 0.4);  // top at 0.5
  ObstacleConfig capsule = obstacle("capsule", ShapeType::kCapsule, Vec3(0.0, 0.0, 0.3));
  capsule.radius = 0.05;  // lying along x (a quarter turn about y): top at 0.35
  capsule.length = 0.4;
  capsule.pose.orientation = Eigen::AngleAxisd(M_PI / 2, Vec3::UnitY());
  ObstacleConfig standing = capsule;  // upright: top at 0.3 + 0.2 + 0.05
  standing.pose.orientation = Eigen::Quaterniond::Identity();
  ObstacleConfig cylinder = obstacle("cylinder", ShapeType::kCylinder, Vec3(0.0, 0.0, 0.3));
  cylinder.radius = 0.05;  // flat top at 0.3 + 0.25
  cylinder.length = 0.5;
  ObstacleConfig plane = obstacle("floor", ShapeType::kPlane, Vec3::Zero());
  plane.normal = Vec3(0.0, 0.0, 2.0);  // not unit: the shape normalises it with its offset
  plane.offset = 0.2;                  // z = 0.1
  const std::vector<std::pair<ObstacleConfig, double>> cases = {
      {box, 0.5}, {capsule, 0.35}, {standing, 0.55}, {cylinder, 0.55}, {plane, 0.1}};
  const PinholeCamera camera = camera320();
  const Frame pose = lookingDown(Vec3(0.0, 0.0, 1.5));
  for (const auto& [shape, top] : cases) {
    const Simulation sim(obstaclesOnly({shape}));
    const Rendered image = render(sim, camera, pose);
    // cx, cy = 159.5, 119.5: the four pixels around the axis look 0.5 px off it in x and y, about
    // 2 mm off the top at 1.15 m; on the crest of a curve of r = 0.05 that lowers the surface by
    // up to (2 * 2.1 mm)^2 / (2 r) = 0.09 mm. Flat tops are exact.
    EXPECT_NEAR(image.at(camera, 159, 119), 1.5 - top, 1e-4) << shape.name;
    EXPECT_NEAR(image.at(camera, 160, 120), 1.5 - top, 1e-4) << shape.name;
  }
  // A cylinder seen from the side: its curved wall at the centre pixel, 1 m - r away.
  ObstacleConfig lying = cylinder;
  lying.pose.orientation = Eigen::AngleAxisd(M_PI / 2, Vec3::UnitX());
  const Simulation sim(obstaclesOnly({lying}));
  const Rendered image = render(sim, camera, pose);
  EXPECT_NEAR(image.at(camera, 160, 120), 1.5 - 0.35, 1e-4);
}

TEST(DepthCamera, RangeLimitsGiveNaNAndANearSurfaceStillOccludes) {
  // A plate 0.05 m under the camera (nearer than range.min 0.1) above a ball: the plate's pixels
  // are NaN, and the ball behind them is not seen through it. Beside the plate the ball is seen;
  // the floor 6 m down is beyond range.max: NaN.
  ObstacleConfig plate = obstacle("plate", ShapeType::kBox, Vec3(-0.1, 0.0, 0.95));
  plate.size = Vec3(0.2, 0.4, 0.01);  // covers x in [-0.2, 0]
  ObstacleConfig ball = obstacle("ball", ShapeType::kSphere, Vec3(0.0, 0.0, 0.0));
  ball.radius = 0.3;
  ObstacleConfig floor = obstacle("floor", ShapeType::kPlane, Vec3::Zero());
  floor.offset = -5.0;
  const Simulation sim(obstaclesOnly({plate, ball, floor}));
  const PinholeCamera camera = camera320();
  const Frame pose = lookingDown(Vec3(0.0, 0.0, 1.0));
  const Rendered image = render(sim, camera, pose);
  int u, v;
  pixelOf(camera, pose, Vec3(-0.01, 0.0, 0.3), u, v);  // under the plate, above the ball
  EXPECT_TRUE(std::isnan(image.at(camera, u, v)));
  pixelOf(camera, pose, Vec3(0.01, 0.0, 0.3), u, v);  // beside the plate: the ball's top
  EXPECT_NEAR(image.at(camera, u, v), 0.7, 1e-3);
  EXPECT_TRUE(std::isnan(image.at(camera, 319, 0)));  // the floor at 6 m
}

TEST(DepthCamera, AParticleInNoTriangleIsDrawnAsItsContactSphere) {
  // A single particle (granular matter and ropes have no triangles) of radius 0.05, 1 m below.
  SceneConfig scene = test::clothScene(1, 2, 1.0, Method::kXpbd);
  scene.cloth.origin = Vec3(0.0, 0.0, 0.0);
  scene.cloth.thickness = 0.05;
  scene.cloth.pinned = {0, 1};
  const Simulation sim(scene);
  ASSERT_TRUE(sim.topology().triangles.empty());
  const PinholeCamera camera = camera320();
  const Frame pose = lookingDown(Vec3(0.0, 0.0, 1.0));
  const Rendered image = render(sim, camera, pose);
  // Half a pixel off the axis in x and y: the sphere's crest is lower there by 0.06 mm.
  EXPECT_NEAR(image.at(camera, 160, 120), 0.95, 1e-4);
  EXPECT_TRUE(std::isnan(image.at(camera, 160 + 30, 120)));  // 0.11 m off the axis: a miss
}

TEST(DepthCamera, NearerSurfaceHidesTheFartherWhicheverIsDrawnFirst) {
  // The cloth (drawn first) above a box (drawn later) and a box above a cloth: nearest wins both.
  SceneConfig scene = test::clothScene(3, 3, 0.2, Method::kXpbd);
  scene.cloth.origin = Vec3(-0.2, 0.2, 0.5);
  scene.cloth.pinned = {0, 1, 2, 3, 4, 5, 6, 7, 8};
  ObstacleConfig box = obstacle("box", ShapeType::kBox, Vec3(0.0, 0.0, 0.2));
  box.size = Vec3(0.1, 0.1, 0.1);
  scene.obstacles = {box};
  const PinholeCamera camera = camera320();
  const Frame pose = lookingDown(Vec3(0.0, 0.0, 1.0));
  EXPECT_NEAR(render(Simulation(scene), camera, pose).at(camera, 160, 120), 0.5, kFloatDepth);
  scene.obstacles[0].pose.position.z() = 0.7;  // top at 0.75, above the cloth
  EXPECT_NEAR(render(Simulation(scene), camera, pose).at(camera, 160, 120), 0.25, kFloatDepth);
}

TEST(DepthCamera, RobotLinksAreSeenAndADisabledLinkIsNot) {
  // test/data/paddle_robot.urdf with its root at z = 0.5: the paddle's sphere (r 0.05) at
  // x = -0.3. Disabled (the node's answer to a link without tf), the link is not drawn.
  Simulation sim(sceneFromYaml(YAML::Load(R"(
cloth: {rows: 1, cols: 2, spacing: 1.0, origin: [100, 100, 100], pinned: [0, 1]}
robot: {urdf_file: paddle_robot.urdf, pose: [0, 0, 0.5, 0, 0, 0, 1]}
)"),
                               std::string(PBD_CLOTH_SOURCE_DIR) + "/test/data"));
  const PinholeCamera camera = camera320();
  const Frame pose = lookingDown(Vec3(-0.3, 0.0, 1.5));
  // Half a pixel off the axis in x and y: the crest is lower there by (2 * 1.8 mm)^2 / 2r.
  EXPECT_NEAR(render(sim, camera, pose).at(camera, 160, 120), 0.95, 1.5e-4);
  const int paddle = sim.robotLinkIndex("paddle");
  ASSERT_GE(paddle, 0);
  sim.setRobotLinkEnabled(paddle, false);
  EXPECT_TRUE(std::isnan(render(sim, camera, pose).at(camera, 160, 120)));
}

TEST(DepthCamera, NoiseIsSeededGaussianOfTheGivenDeviation) {
  const std::size_t n = 320 * 240;
  const std::vector<float> clean(n, 1.0f);
  std::vector<float> a = clean, b = clean, c = clean, d = clean;
  addDepthNoise(a.data(), n, 0.01, 7, 3, 0.1, 5.0);
  addDepthNoise(b.data(), n, 0.01, 7, 3, 0.1, 5.0);
  addDepthNoise(c.data(), n, 0.01, 7, 4, 0.1, 5.0);  // next frame
  addDepthNoise(d.data(), n, 0.01, 8, 3, 0.1, 5.0);  // other seed
  EXPECT_EQ(a, b);
  EXPECT_NE(a, c);
  EXPECT_NE(a, d);
  double sum = 0.0, sum2 = 0.0;
  for (float z : a) {
    sum += z - 1.0;
    sum2 += (z - 1.0) * (z - 1.0);
  }
  const double mean = sum / n, deviation = std::sqrt(sum2 / n - mean * mean);
  // 76800 samples: the sample deviation is within 1 % of sigma with overwhelming probability
  // (its relative standard error is 1 / sqrt(2 n) = 0.26 %), the mean within 4 standard errors.
  EXPECT_NEAR(deviation, 0.01, 1e-4);
  EXPECT_NEAR(mean, 0.0, 4 * 0.01 / std::sqrt(double(n)));
  // Nothing seen stays nothing seen; noise never brings a pixel outside the range.
  std::vector<float> edge(1000, 0.1f);
  edge[0] = std::nanf("");
  addDepthNoise(edge.data(), edge.size(), 0.05, 1, 1, 0.1, 5.0);
  EXPECT_TRUE(std::isnan(edge[0]));
  int pushed_out = 0;
  for (float z : edge) {
    pushed_out += std::isnan(z);
    if (!std::isnan(z)) EXPECT_GE(z, 0.1f);
  }
  EXPECT_GT(pushed_out, 300);  // about half of them went below range.min
}

TEST(DepthCameraConfig, CamerasAreReadWithDefaultsAndCheckedKeyByKey) {
  const SceneConfig scene = sceneFromYaml(YAML::Load(R"(
cameras:
  - {name: head_camera, frame: head_optical, pose: [], width: 64, height: 48}
  - {name: side, frame: side_optical, pose: [1, 0, 1, 0, 0, 0, 1], cx: 10, range: {min: 0.2, max: 3}, noise: 0.002, seed: 5}
)"));
  ASSERT_EQ(scene.cameras.size(), 2u);
  EXPECT_FALSE(scene.cameras[0].has_pose);
  EXPECT_DOUBLE_EQ(scene.cameras[0].cx, 31.5);
  EXPECT_DOUBLE_EQ(scene.cameras[0].cy, 23.5);
  EXPECT_DOUBLE_EQ(scene.cameras[0].rate, 15.0);
  EXPECT_TRUE(scene.cameras[1].has_pose);
  EXPECT_DOUBLE_EQ(scene.cameras[1].pose.position.x(), 1.0);
  EXPECT_DOUBLE_EQ(scene.cameras[1].cx, 10.0);
  EXPECT_DOUBLE_EQ(scene.cameras[1].range_max, 3.0);
  EXPECT_EQ(scene.cameras[1].seed, 5);

  const auto refused = [](const std::string& yaml) -> std::string {
    try {
      sceneFromYaml(YAML::Load(yaml));
    } catch (const ConfigError& e) {
      return e.what();
    }
    return "accepted";
  };
  EXPECT_NE(refused("cameras: [{name: c, frame: f, width: 0}]").find("cameras[0].width"),
            std::string::npos);
  EXPECT_NE(refused("cameras: [{name: c, frame: f, width: 100000}]").find("cameras[0].width"),
            std::string::npos);
  EXPECT_NE(
      refused("step_rate: 60\ncameras: [{name: c, frame: f, rate: 120}]").find("cameras[0].rate"),
      std::string::npos);
  EXPECT_NE(refused("cameras: [{name: c, frame: f, range: {min: 2, max: 1}}]")
                .find("cameras[0].range.max"),
            std::string::npos);
  EXPECT_NE(refused("cameras: [{name: c, frame: f, fx: -1}]").find("cameras[0].fx"),
            std::string::npos);
  EXPECT_NE(refused("cameras: [{name: c, frame: f, noise: -0.1}]").find("cameras[0].noise"),
            std::string::npos);
  EXPECT_NE(refused("cameras: [{name: c, frame: ''}]").find("cameras[0].frame"), std::string::npos);
  EXPECT_NE(refused("cameras: [{name: c, frame: f, fov: 60}]").find("cameras[0].fov"),
            std::string::npos);
  EXPECT_NE(refused("cameras: [{name: c, frame: f, pose: [0, 0, 1]}]").find("cameras[0].pose"),
            std::string::npos);
  EXPECT_NE(
      refused("grippers: [{name: c}]\ncameras: [{name: c, frame: f}]").find("cameras[0].name"),
      std::string::npos);
}

}  // namespace
}  // namespace pbd_cloth
