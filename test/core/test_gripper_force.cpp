// The force the held particles exert on a gripper (Simulation::gripperForce): a cloth hanging
// from one gripper at rest pulls it down with its whole weight, in every method, whatever
// constraints carry the load (stretch, bending, tethers, contacts); accelerating it upwards takes
// more.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include "collision_scenes.h"
#include "pbd_cloth/sim/simulation.h"

namespace pbd_cloth {
namespace {

using test::kGravity;

const char* name(Method method) { return toString(method); }

// A 10 x 10 cloth of 0.1 kg, 5 cm spacing, hanging in the x-z plane (top row at z = 1) with
// nothing pinned: one gripper, radius 3 cm, grasps the two middle particles of the top row at
// t = 0 and holds the whole cloth. Bending and tethers on, damped so that it comes to rest.
SceneConfig hangingFromGripper(Method method) {
  SceneConfig scene = test::clothScene(10, 10, 0.05, method);
  scene.cloth.mass = 0.1;
  scene.cloth.origin = Vec3(0.0, 0.0, 1.0);
  scene.cloth.rpy = Vec3(test::kPiValue / 2.0, 0.0, 0.0);
  scene.cloth.bend_compliance = 1e-4;
  scene.cloth.tethers = method != Method::kMassSpring;
  scene.solver.substeps = 8;
  scene.solver.iterations = 4;
  scene.solver.damping = 2.0;
  scene.solver.spring_stiffness = 100.0;  // stable at h = 1/480 s for 1 g particles
  scene.solver.spring_damping = 0.005;    // the springs' own swing dies away too
  scene.solver.bend_spring_stiffness = 1e-4;
  GripperConfig gripper;
  gripper.name = "hand";
  gripper.radius = 0.03;
  Waypoint start;
  start.t = 0.0;
  start.pose = test::makePose(Vec3(0.225, 0.0, 1.0));
  start.grasp = 1;
  gripper.trajectory = {start};
  scene.grippers = {gripper};
  return scene;
}

double totalMass(const Simulation& sim) {
  double mass = 0.0;
  for (double m : sim.particles().mass) mass += m;
  return mass;
}

// Mean of the gripper force over `steps` steps.
Vec3 meanForce(Simulation& sim, int steps) {
  Vec3 sum = Vec3::Zero();
  for (int k = 0; k < steps; ++k) {
    sim.step();
    sum += sim.gripperForce(0);
  }
  return sum / steps;
}

// After 12 s the cloth hangs still (mass_spring's explicit cloth buckles out of its plane at first
// and takes that long to come to rest again): the force is its weight, total mass times g, within 2
// %, and points down within 1 degree. The gripper holds only 2 of the 100 particles, so the load
// the others put on it through the constraints is what is measured.
TEST(GripperForce, HangingClothPullsWithItsWeightInEveryMethod) {
  for (Method method : {Method::kXpbd, Method::kPbd, Method::kVerlet, Method::kMassSpring}) {
    Simulation sim(hangingFromGripper(method));
    for (int k = 0; k < 720; ++k) sim.step();
    ASSERT_EQ(sim.collisions().stats().particle_pairs, 0);
    int held = 0;
    for (int i = 0; i < sim.particles().size(); ++i) held += sim.particles().isKinematic(i);
    ASSERT_EQ(held, 2) << name(method);
    const Vec3 force = meanForce(sim, 30);
    const double weight = totalMass(sim) * kGravity;
    std::printf("%s: |F| = %.5f N, weight %.5f N, %.3f %% off, %.4f deg from down\n", name(method),
                force.norm(), weight, 100.0 * (force.norm() - weight) / weight,
                std::acos(-force.normalized().z()) * 180.0 / test::kPiValue);
    EXPECT_NEAR(force.norm(), weight, 0.02 * weight) << name(method);
    EXPECT_GT(-force.normalized().z(), std::cos(test::toRadians(1.0))) << name(method);
  }
}

// The same cloth lifted: at rest the gripper carries the weight W; moved upwards with a constant
// acceleration a (live poses, z = z0 + a t^2 / 2) it must carry M (g + a) once the cloth follows,
// plus the drag of solver.damping on the free particles, M_free c v. Over the second half of 0.5 s
// at a = 2 m/s^2 the mean force lies within 5 % of that, i.e. clearly above W (M a = 20 % of W).
TEST(GripperForce, AcceleratingUpwardsTakesMoreThanHoldingStill) {
  for (Method method : {Method::kXpbd, Method::kMassSpring}) {
    Simulation sim(hangingFromGripper(method));
    for (int k = 0; k < 720; ++k) sim.step();
    const double rest = meanForce(sim, 30).norm();
    const double accel = 2.0, dt = 1.0 / sim.scene().step_rate;
    const Vec3 start = sim.grippers().pose(0).position;
    Vec3 lifting = Vec3::Zero();
    double mean_speed = 0.0;
    const int steps = 30, counted = steps - steps / 2;
    for (int k = 1; k <= steps; ++k) {
      const double t = k * dt;
      sim.setGripperPose(0, test::makePose(start + Vec3(0.0, 0.0, 0.5 * accel * t * t)));
      sim.step();
      if (k > steps / 2) {
        lifting += sim.gripperForce(0) / counted;
        mean_speed += accel * (t - 0.5 * dt) / counted;  // the gripper's speed in this step
      }
    }
    double free_mass = 0.0;
    for (int i = 0; i < sim.particles().size(); ++i) {
      if (!sim.particles().isKinematic(i)) free_mass += sim.particles().mass[i];
    }
    const double expected =
        totalMass(sim) * (kGravity + accel) + free_mass * sim.scene().solver.damping * mean_speed;
    std::printf("%s: at rest %.5f N, lifting at %.1f m/s^2 %.5f N (M (g + a) + drag = %.5f N)\n",
                name(method), rest, accel, lifting.norm(), expected);
    EXPECT_GT(lifting.norm(), rest * (1.0 + 0.5 * accel / kGravity)) << name(method);
    EXPECT_NEAR(lifting.norm(), expected, 0.05 * expected) << name(method);
    EXPECT_LT(lifting.z(), 0.0) << name(method);
  }
}

// Contacts carry load too: a 0.5 kg granular ball resting on top of a held particle (a 1 x 2 cloth
// of 2 x 1 kg held by one particle, the other hanging below it) adds its weight to the gripper's.
TEST(GripperForce, BallRestingOnAHeldParticleAddsItsWeight) {
  for (Method method : {Method::kXpbd, Method::kPbd, Method::kVerlet, Method::kMassSpring}) {
    SceneConfig scene = test::clothScene(1, 2, 0.1, method);
    scene.cloth.origin = Vec3(0.0, 0.0, 1.0);
    scene.cloth.rpy = Vec3(0.0, test::kPiValue / 2.0, 0.0);  // grid +x becomes -z: a column
    scene.cloth.thickness = 0.02;
    scene.solver.substeps = 8;
    scene.solver.iterations = 4;
    scene.solver.damping = 2.0;
    scene.solver.spring_stiffness = 1e4;
    scene.granular.count = 1;
    scene.granular.radius = 0.02;
    scene.granular.mass = 0.5;
    scene.granular.region_min = Vec3(-0.02, -0.02, 1.02);  // the ball's centre at (0, 0, 1.04)
    scene.granular.region_max = Vec3(0.03, 0.03, 1.07);
    scene.cloth.friction.static_coefficient = 0.5;
    scene.cloth.friction.kinetic_coefficient = 0.5;
    GripperConfig gripper;
    gripper.name = "hand";
    gripper.radius = 0.01;
    Waypoint start;
    start.pose = test::makePose(Vec3(0.0, 0.0, 1.0));
    start.grasp = 1;
    gripper.trajectory = {start};
    scene.grippers = {gripper};
    Simulation sim(scene);
    const Particles& p = sim.particles();
    ASSERT_LT((p.position[0] - Vec3(0.0, 0.0, 1.0)).norm(), 1e-9);
    ASSERT_LT((p.position[1] - Vec3(0.0, 0.0, 0.9)).norm(), 1e-9);
    sim.mutableParticles().position[2] = Vec3(0.0, 0.0, 1.0 + p.radius[0] + p.radius[2]);
    for (int k = 0; k < 120; ++k) sim.step();
    ASSERT_TRUE(p.isKinematic(0));
    ASSERT_FALSE(p.isKinematic(1));
    EXPECT_NEAR(p.position[2].z(), 1.0 + p.radius[0] + p.radius[2], 0.01 * p.radius[2])
        << "the ball does not rest on the held particle";
    const Vec3 force = meanForce(sim, 30);
    const double weight = (p.mass[0] + p.mass[1] + p.mass[2]) * kGravity;
    std::printf("%s: |F| = %.4f N, weight %.4f N\n", name(method), force.norm(), weight);
    EXPECT_NEAR(force.z(), -weight, 0.02 * weight) << name(method);
    EXPECT_LT(force.head<2>().norm(), 0.01 * weight) << name(method);
  }
}

}  // namespace
}  // namespace pbd_cloth
