// The robot's links as colliders (issue 10), with a robot model built in code (the URDF reader has
// tests of its own): every collision element of a link collides, links posed by forward kinematics
// of robot.joint_trajectory sweep the cloth continuously, and a disabled link is left out.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>

#include "collision_scenes.h"
#include "mesh_builders.h"
#include "pbd_cloth/sim/simulation.h"

namespace pbd_cloth {
namespace {

using test::makePose;

ObstacleConfig element(ShapeType shape, const Pose& origin) {
  ObstacleConfig o;
  o.shape = shape;
  o.pose = origin;
  o.radius = 0.04;
  o.length = 0.3;
  o.size = Vec3(0.08, 0.08, 0.3);
  return o;
}

// A base link and, on a prismatic joint along y, a "paddle" link with one element of every kind
// side by side along x (sphere, box, cylinder, mesh).
RobotModel paddleRobot() {
  RobotModel model;
  model.name = "paddle_robot";
  RobotLink base;
  base.name = "base";
  RobotLink paddle;
  paddle.name = "paddle";
  paddle.collisions.push_back(element(ShapeType::kSphere, makePose(Vec3(-0.3, 0, 0.5))));
  paddle.collisions.push_back(element(ShapeType::kBox, makePose(Vec3(-0.1, 0, 0.5))));
  paddle.collisions.push_back(element(ShapeType::kCylinder, makePose(Vec3(0.1, 0, 0.5))));
  paddle.collisions.push_back(
      test::meshObstacle("m", test::icosphere(0.04, 2), makePose(Vec3(0.3, 0, 0.5))));
  for (std::size_t e = 0; e < paddle.collisions.size(); ++e) {
    paddle.collisions[e].name = "paddle/" + std::to_string(e);
    paddle.collisions[e].has_friction = true;
    paddle.collisions[e].friction.static_coefficient = 0.0;
    paddle.collisions[e].friction.kinetic_coefficient = 0.0;
  }
  paddle.parent_joint = 0;
  model.links = {base, paddle};
  RobotJoint slide;
  slide.name = "slide";
  slide.type = JointType::kPrismatic;
  slide.parent_link = 0;
  slide.child_link = 1;
  slide.axis = Vec3::UnitY();
  model.joints = {slide};
  model.root_link = 0;
  return model;
}

// A cloth hanging in the x-z plane (y = 0), 1 m wide, from z = 1.0 down to 0.
SceneConfig curtainScene(int substeps) {
  SceneConfig scene = test::clothScene(34, 34, 0.03, Method::kXpbd);
  scene.step_rate = 120.0;
  scene.solver.substeps = substeps;
  scene.cloth.mass = 0.2;
  scene.cloth.thickness = 0.005;
  scene.cloth.origin = Vec3(-0.495, 0.0, 1.0);
  scene.cloth.rpy = Vec3(M_PI / 2.0, 0.0, 0.0);
  scene.cloth.pinned = {0, 33};
  scene.robot.enabled = true;
  scene.robot.model = paddleRobot();
  // The paddle starts clear of the cloth, 30 cm in front of it.
  scene.robot.joint_trajectory = {{0.0, {{"slide", -0.3}}}};
  return scene;
}

// The paddle sweeps along y at 2 m/s from y = -0.3 through the curtain, posed by forward
// kinematics of the joint trajectory. Every step ends with no particle inside any element, and
// each element has cloth resting against it: all four collide, none is left out.
TEST(RobotLinks, EveryElementOfAMovingLinkPushesTheCloth) {
  SceneConfig scene = curtainScene(10);
  scene.robot.joint_trajectory = {{0.0, {{"slide", -0.3}}}, {0.3, {{"slide", 0.3}}}};
  Simulation sim(scene);
  ASSERT_EQ(sim.robotLinks().count(), 2);
  EXPECT_FALSE(sim.robotLinks().hasCollision(0));
  EXPECT_TRUE(sim.robotLinks().hasCollision(1));
  double worst = 0.0;
  for (int k = 0; k < 36; ++k) {
    sim.step();
    worst = std::max(worst, sim.stats().max_penetration);
  }
  EXPECT_NEAR(sim.robotLinks().pose(1).position.y(), 0.3, 1e-12);
  std::printf("[ measured ] paddle of 4 elements at 2 m/s: max penetration %.3g m\n", worst);
  EXPECT_LT(worst, scene.cloth.thickness);
  // Each element carries cloth: a particle in contact with it (within 1 mm of its surface).
  const auto& colliders = sim.collisions().obstacles();
  for (std::size_t e = 0; e < 4; ++e) {
    const int k = static_cast<int>(e) + sim.obstacleCount();
    const Shape& shape = colliders[k].shape;
    const Frame frame = frameFromPose(colliders[k].pose);
    int touching = 0;
    for (int i = 0; i < sim.particles().cloth_count; ++i) {
      const double d = signedDistance(shape, frame.toLocal(sim.particles().position[i]));
      if (d < scene.cloth.thickness + 1e-3) ++touching;
    }
    EXPECT_GT(touching, 0) << toString(colliders[k].shape.type) << " element carries no cloth";
  }
}

// The same sweep with the link's pose given live (as the node does from tf), and with the link
// disabled: then the cloth is not touched at all and stays at y = 0.
TEST(RobotLinks, LivePosesAndDisabledLinks) {
  for (bool enabled : {true, false}) {
    Simulation sim(curtainScene(10));
    sim.setRobotLinkEnabled(1, enabled);
    for (int k = 1; k <= 36; ++k) {
      sim.setRobotLinkPose(1, makePose(Vec3(0.0, -0.3 + 2.0 * k / 120.0, 0.0)));
      sim.step();
    }
    double max_y = 0.0;
    for (int i = 0; i < sim.particles().cloth_count; ++i) {
      max_y = std::max(max_y, sim.particles().position[i].y());
    }
    if (enabled) {
      EXPECT_GT(max_y, 0.2);
      EXPECT_LT(sim.stats().max_penetration, 0.005);
    } else {
      EXPECT_LT(max_y, 1e-6);
    }
  }
}

// Enabled again after being away, a link appears where it is now: it does not sweep the cloth
// along the way it moved while it was not followed.
TEST(RobotLinks, ReEnabledLinkDoesNotSweepTheWayItWasAway) {
  Simulation sim(curtainScene(10));
  sim.setRobotLinkPose(1, makePose(Vec3(0.0, -0.3, 0.0)));
  sim.step();
  sim.setRobotLinkEnabled(1, false);
  sim.setRobotLinkPose(1, makePose(Vec3(0.0, 0.5, 0.0)));  // beyond the cloth
  sim.step();
  sim.setRobotLinkEnabled(1, true);
  sim.setRobotLinkPose(1, makePose(Vec3(0.0, 0.5, 0.0)));
  sim.step();
  double max_y = 0.0;
  for (int i = 0; i < sim.particles().cloth_count; ++i) {
    max_y = std::max(max_y, sim.particles().position[i].y());
  }
  EXPECT_LT(max_y, 1e-6);
}

TEST(RobotLinks, PaddingAndFrictionPerRobot) {
  SceneConfig scene = curtainScene(10);
  for (auto& element : scene.robot.model.links[1].collisions) element.padding = 0.02;
  Simulation sim(scene);
  const auto& colliders = sim.collisions().obstacles();
  ASSERT_EQ(colliders.size(), 4u);
  // A padded sphere is a larger sphere.
  EXPECT_NEAR(signedDistance(colliders[0].shape, Vec3(0.1, 0.0, 0.0)), 0.1 - 0.06, 1e-15);
  EXPECT_TRUE(colliders[0].has_friction);
}

TEST(RobotLinks, UnknownJointAndMissingModelAreRefused) {
  SceneConfig scene = curtainScene(10);
  scene.robot.joint_trajectory = {{0.0, {{"elbow", 0.3}}}};
  try {
    Simulation sim(scene);
    FAIL() << "a joint the model lacks was accepted";
  } catch (const ConfigError& error) {
    EXPECT_NE(std::string(error.what()).find("elbow"), std::string::npos) << error.what();
  }
  scene = curtainScene(10);
  scene.robot.model = RobotModel();
  EXPECT_THROW(Simulation{scene}, ConfigError);
}

}  // namespace
}  // namespace pbd_cloth
