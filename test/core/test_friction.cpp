// Contact at rest and position-level Coulomb friction (collision seed, eq. friction_correction)
// against the answers of REFERENCE_CASES.md cases 9 (resting particle) and 10 (inclined plane,
// sliding to rest), and friction relative to a moving shape.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <memory>

#include "collision_scenes.h"
#include "pbd_cloth/sim/simulation.h"

namespace pbd_cloth {
namespace {

using test::kGravity;
using test::kPoint;

// Case 9: a particle resting on a plane for 1e4 steps. Penetration, jitter (std of the height) and
// speed must all stay below 1e-6 r, for every method.
TEST(CollisionResting, ParticleOnPlaneNeitherSinksNorJitters) {
  const double r = 0.01;
  for (Method method : {Method::kXpbd, Method::kPbd, Method::kVerlet}) {
    SceneConfig scene = test::pointParticleScene(r, Vec3(0.3, -0.2, r));
    scene.solver.method = method;
    scene.solver.substeps = 10;
    scene.obstacles = {test::plane("floor", Vec3::UnitZ(), 0.0)};
    Simulation sim(scene);
    double sum = 0.0, sum_squares = 0.0, max_penetration = 0.0, max_speed = 0.0;
    const int steps = 10000;
    for (int k = 0; k < steps; ++k) {
      sim.step();
      const double z = sim.particles().position[kPoint].z();
      sum += z;
      sum_squares += z * z;
      max_penetration = std::max(max_penetration, r - z);
      max_speed = std::max(max_speed, sim.particles().velocity[kPoint].norm());
    }
    const double mean = sum / steps;
    const double jitter = std::sqrt(std::max(0.0, sum_squares / steps - mean * mean));
    EXPECT_LT(max_penetration, 1e-6 * r) << toString(method);
    EXPECT_LT(jitter, 1e-6 * r) << toString(method);
    EXPECT_LT(max_speed, 1e-6 * r) << toString(method);
    EXPECT_LT(sim.stats().max_penetration, 1e-6 * r) << toString(method);
    std::printf("%s: penetration %.2e m, jitter %.2e m, speed %.2e m/s (r = %g m)\n",
                toString(method), max_penetration, jitter, max_speed, r);
  }
}

// The same with cloth particles: a 2-particle rope lying on the floor rests at z = thickness.
TEST(CollisionResting, RopeOnPlaneRestsAtThickness) {
  SceneConfig scene = test::clothScene(1, 2, 0.05, Method::kXpbd);
  scene.cloth.thickness = 0.004;
  scene.cloth.origin = Vec3(0.0, 0.0, 0.004);
  scene.solver.substeps = 10;
  scene.obstacles = {test::plane("floor", Vec3::UnitZ(), 0.0)};
  Simulation sim(scene);
  for (int k = 0; k < 10000; ++k) sim.step();
  for (int i = 0; i < 2; ++i) {
    EXPECT_NEAR(sim.particles().position[i].z(), 0.004, 1e-6 * 0.004);
    EXPECT_LT(sim.particles().velocity[i].norm(), 1e-6 * 0.004);
  }
}

// A particle on top of each shape (box turned about z, capsule lying along x, sphere) stays put.
TEST(CollisionResting, ParticleRestsOnEveryShape) {
  const double r = 0.01;
  const Eigen::Quaterniond turned(Eigen::AngleAxisd(0.5, Vec3::UnitZ()));
  const Eigen::Quaterniond lying(Eigen::AngleAxisd(test::kPiValue / 2.0, Vec3::UnitY()));
  const ObstacleConfig shapes[] = {
      test::box("table", Vec3(0.4, 0.3, 0.1), test::makePose(Vec3(0.0, 0.0, -0.05), turned)),
      test::capsule("rod", 0.02, 0.5, test::makePose(Vec3(0.0, 0.0, -0.02), lying)),
      test::sphere("ball", 0.2, test::makePose(Vec3(0.0, 0.0, -0.2)))};
  for (const ObstacleConfig& shape : shapes) {
    SceneConfig scene = test::pointParticleScene(r, Vec3(0.0, 0.0, r));
    scene.obstacles = {shape};
    Simulation sim(scene);
    for (int k = 0; k < 1000; ++k) sim.step();
    const Vec3 x = sim.particles().position[kPoint];
    EXPECT_NEAR(x.z(), r, 1e-6 * r) << shape.name;
    EXPECT_LT(std::hypot(x.x(), x.y()), 1e-6 * r) << shape.name;
    EXPECT_LT(sim.stats().max_penetration, 1e-6 * r) << shape.name;
  }
}

// Case 10: a particle on a plane inclined by theta (normal (-sin, 0, cos), so downhill is -x).
class Incline {
 public:
  Incline(double degrees, int substeps, double step_rate = 60.0) {
    const double theta = test::toRadians(degrees);
    normal_ = Vec3(-std::sin(theta), 0.0, std::cos(theta));
    downhill_ = -Vec3(std::cos(theta), 0.0, std::sin(theta));
    const double r = 0.01;
    SceneConfig scene = test::pointParticleScene(r, r * normal_);
    scene.step_rate = step_rate;
    scene.solver.substeps = substeps;
    scene.cloth.friction.static_coefficient = 0.5;
    scene.cloth.friction.kinetic_coefficient = 0.4;
    scene.obstacles = {test::plane("slope", normal_, 0.0)};
    sim_ = std::make_unique<Simulation>(scene);
    start_ = sim_->particles().position[kPoint];
  }
  void run(double seconds) {
    const int steps = static_cast<int>(std::lround(seconds * sim_->scene().step_rate));
    for (int k = 0; k < steps; ++k) sim_->step();
  }
  double distance() const { return (sim_->particles().position[kPoint] - start_).dot(downhill_); }
  double displacement() const { return (sim_->particles().position[kPoint] - start_).norm(); }
  double speed() const { return sim_->particles().velocity[kPoint].dot(downhill_); }
  double height() const { return sim_->particles().position[kPoint].dot(normal_); }

 private:
  Vec3 normal_, downhill_, start_;
  std::unique_ptr<Simulation> sim_;
};

// Sticks while tan(theta) <= mu_s, with no creep (< 1e-9 m over 10 s); slides just above.
TEST(CollisionFriction, InclineSticksBelowCriticalAngleWithoutCreep) {
  for (int substeps : {1, 10}) {
    for (double degrees : {10.0, 20.0, 26.5}) {
      Incline incline(degrees, substeps);
      incline.run(10.0);
      EXPECT_LT(incline.displacement(), 1e-9) << degrees << " deg, " << substeps << " substeps";
      EXPECT_NEAR(incline.height(), 0.01, 1e-9);
    }
    Incline sliding(26.63, substeps);
    sliding.run(1.0);
    // a = g (sin - mu_k cos) = 0.889 m/s^2: 0.44 m in the first second.
    EXPECT_GT(sliding.distance(), 0.4) << substeps << " substeps";
  }
}

// The critical angle, found by bisection on "moved more than 1e-9 m in 0.5 s": atan(mu_s) =
// 26.565 deg, within +-0.05 deg.
TEST(CollisionFriction, CriticalAngleIsArctanOfStaticCoefficient) {
  double stuck = 20.0, slides = 35.0;
  while (slides - stuck > 0.005) {
    const double middle = 0.5 * (stuck + slides);
    Incline incline(middle, 10);
    incline.run(0.5);
    (incline.displacement() > 1e-9 ? slides : stuck) = middle;
  }
  const double critical = 0.5 * (stuck + slides);
  const double expected = std::atan(0.5) * 180.0 / test::kPiValue;  // 26.5651 deg
  std::printf("critical angle %.4f deg (exact %.4f)\n", critical, expected);
  EXPECT_NEAR(critical, expected, 0.05);
}

// Above the critical angle a = g (sin theta - mu_k cos theta): 0.957337 (27 deg), 1.506716 (30),
// 4.162031 (45), 6.533709 (60) m/s^2, within 1 %. Measured from the speed gained over 0.5 s.
TEST(CollisionFriction, SlidingAccelerationIsCoulomb) {
  const double angles[] = {27.0, 30.0, 45.0, 60.0};
  const double expected[] = {0.957337, 1.506716, 4.162031, 6.533709};
  for (int k = 0; k < 4; ++k) {
    Incline incline(angles[k], 10);
    incline.run(0.5);
    const double v0 = incline.speed();
    incline.run(0.5);
    const double acceleration = (incline.speed() - v0) / 0.5;
    std::printf("%.0f deg: a = %.6f m/s^2 (exact %.6f)\n", angles[k], acceleration, expected[k]);
    EXPECT_NEAR(acceleration, expected[k], 0.01 * expected[k]) << angles[k] << " deg";
    // The particle keeps sliding on the surface, neither lifting off nor sinking.
    EXPECT_NEAR(incline.height(), 0.01, 1e-9);
  }
}

// From 2 m/s on flat ground it slides v0^2 / (2 mu_k g) = 0.509684 m. The discrete kinetic law
// removes mu_k g h of speed per substep, which shortens the slide by v0 h / 2, and static friction
// takes over within the last step (friction window of a step, contact.h), which can stop it up to
// the travel of that step, mu_k g dt^2 / 2, early: with h = 1/6000 s and dt = 1/60 s the answer
// must be within v0 h / 2 + mu_k g dt^2 / 2 = 7.1e-4 m (0.14 %).
TEST(CollisionFriction, SlidesToRestOnFlatGround) {
  const double r = 0.01, v0 = 2.0;
  SceneConfig scene = test::pointParticleScene(r, Vec3(0.0, 0.0, r));
  scene.solver.substeps = 100;
  scene.obstacles = {test::plane("floor", Vec3::UnitZ(), 0.0)};
  Simulation sim(scene);
  sim.mutableParticles().velocity[kPoint] = Vec3(v0, 0.0, 0.0);
  for (int k = 0; k < 60; ++k) sim.step();  // 1 s: stops after v0 / (mu_k g) = 0.51 s
  const double distance = sim.particles().position[kPoint].x();
  const double expected = v0 * v0 / (2.0 * 0.4 * kGravity);
  const double dt = 1.0 / 60.0, h = dt / 100;
  const double tolerance = 0.5 * v0 * h + 0.5 * 0.4 * kGravity * dt * dt;
  std::printf("slid %.6f m (exact %.6f, tolerance %.2e)\n", distance, expected, tolerance);
  EXPECT_NEAR(distance, expected, tolerance);
  EXPECT_LT(sim.particles().velocity[kPoint].norm(), 1e-9);  // at rest (static friction holds)
}

// Friction acts on the displacement relative to the shape: a cloth lying on a box that starts to
// move at u = 0.5 m/s is dragged along at mu_k g until it moves with the box (t* = u / (mu_k g)),
// so at T = 0.5 s it has moved u (T - t*) + mu_k g t*^2 / 2 = 0.2182 m. Without friction it stays.
TEST(CollisionFriction, MovingBoxDragsClothByKineticFriction) {
  const double u = 0.5, mu_k = 0.4;
  auto drag = [&](double mu_s, double mu) {
    SceneConfig scene = test::clothScene(6, 6, 0.02, Method::kXpbd);
    scene.step_rate = 120.0;
    scene.solver.substeps = 20;
    scene.cloth.origin = Vec3(-0.05, 0.05, 0.005);  // lying on the box top (z = 0)
    scene.cloth.friction.static_coefficient = mu_s;
    scene.cloth.friction.kinetic_coefficient = mu;
    scene.obstacles = {test::box("cart", Vec3(0.6, 0.6, 0.1), test::makePose(Vec3(0, 0, -0.05)))};
    Simulation sim(scene);
    const double x0 = test::clothCentroid(sim).x();
    const double dt = 1.0 / scene.step_rate;
    for (int k = 1; k <= 60; ++k) {
      sim.setObstaclePose(0, test::makePose(Vec3(u * k * dt, 0.0, -0.05)));
      sim.step();
    }
    EXPECT_LT(test::obstaclePenetration(sim), 1e-6);
    return test::clothCentroid(sim).x() - x0;
  };
  const double t_star = u / (mu_k * kGravity);
  const double expected = u * (0.5 - t_star) + 0.5 * mu_k * kGravity * t_star * t_star;
  const double dragged = drag(0.5, mu_k);
  std::printf("dragged %.5f m (Coulomb %.5f m)\n", dragged, expected);
  // The discrete law lags by about one substep at each end of the sliding phase: 2 u h = 4e-4 m.
  EXPECT_NEAR(dragged, expected, 1e-3);
  EXPECT_NEAR(drag(0.0, 0.0), 0.0, 1e-9);
}

}  // namespace
}  // namespace pbd_cloth
