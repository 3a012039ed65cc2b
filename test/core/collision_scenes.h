// Scenes and measurements of the contact tests (test_collisions.cpp, test_friction.cpp,
// test_granular.cpp, test_self_collision.cpp): point particles on shapes, obstacles by name, and
// the probes the reference cases (../shared/REFERENCE_CASES.md, cases 9-14) measure.
#pragma once

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <string>

#include "pbd_cloth/config/scene_config.h"
#include "pbd_cloth/geometry/shapes.h"
#include "pbd_cloth/sim/simulation.h"
#include "test_scenes.h"

namespace pbd_cloth {
namespace test {

constexpr double kPiValue = 3.14159265358979323846;
constexpr double kGravity = 9.81;

inline double toRadians(double degrees) { return degrees * kPiValue / 180.0; }

inline Pose makePose(const Eigen::Vector3d& position,
                     const Eigen::Quaterniond& orientation = Eigen::Quaterniond::Identity()) {
  Pose pose;
  pose.position = position;
  pose.orientation = orientation;
  return pose;
}

inline ObstacleConfig plane(const std::string& name, const Eigen::Vector3d& normal, double offset) {
  ObstacleConfig o;
  o.name = name;
  o.shape = ShapeType::kPlane;
  o.normal = normal;
  o.offset = offset;
  return o;
}

inline ObstacleConfig sphere(const std::string& name, double radius, const Pose& pose) {
  ObstacleConfig o;
  o.name = name;
  o.shape = ShapeType::kSphere;
  o.radius = radius;
  o.pose = pose;
  return o;
}

inline ObstacleConfig box(const std::string& name, const Eigen::Vector3d& size, const Pose& pose) {
  ObstacleConfig o;
  o.name = name;
  o.shape = ShapeType::kBox;
  o.size = size;
  o.pose = pose;
  return o;
}

inline ObstacleConfig capsule(const std::string& name, double radius, double length,
                              const Pose& pose) {
  ObstacleConfig o;
  o.name = name;
  o.shape = ShapeType::kCapsule;
  o.radius = radius;
  o.length = length;
  o.pose = pose;
  return o;
}

// One free granular particle of 1 kg at `position` and nothing else that moves: the cloth the
// scene needs (rows * cols >= 2) is two pinned particles 100 m away. The particle is index 2.
constexpr int kPoint = 2;
inline SceneConfig pointParticleScene(double radius, const Eigen::Vector3d& position) {
  SceneConfig scene = clothScene(1, 2, 0.1, Method::kXpbd);
  scene.cloth.origin = Eigen::Vector3d(100.0, 100.0, 100.0);
  scene.cloth.pinned = {0, 1};
  scene.granular.count = 1;
  scene.granular.radius = radius;
  scene.granular.mass = 1.0;
  // The builder puts the first granular particle at region.min + (r, r, r).
  scene.granular.region_min = position - Eigen::Vector3d::Constant(radius);
  scene.granular.region_max = position + Eigen::Vector3d::Constant(radius);
  return scene;
}

// Deepest penetration of any free particle into the obstacles as they stand now (m).
inline double obstaclePenetration(const Simulation& sim) {
  double depth = 0.0;
  const Particles& p = sim.particles();
  for (int k = 0; k < sim.obstacleCount(); ++k) {
    const Shape& shape = sim.obstacle(k).shape;
    const Frame frame = frameFromPose(sim.obstacle(k).pose);
    for (int i = 0; i < p.size(); ++i) {
      if (p.isKinematic(i)) continue;
      depth = std::max(depth, p.radius[i] - signedDistance(shape, frame.toLocal(p.position[i])));
    }
  }
  return depth;
}

// Mean position of the cloth particles.
inline Eigen::Vector3d clothCentroid(const Simulation& sim) {
  Eigen::Vector3d sum = Eigen::Vector3d::Zero();
  for (int i = 0; i < sim.particles().cloth_count; ++i) sum += sim.particles().position[i];
  return sum / sim.particles().cloth_count;
}

}  // namespace test
}  // namespace pbd_cloth
