#include "pbd_cloth/sim/colliders.h"

namespace pbd_cloth {

Shape makeShape(const ObstacleConfig& obstacle) {
  Shape shape;
  shape.type = obstacle.shape;
  shape.radius = obstacle.radius;
  shape.half_length = 0.5 * obstacle.length;
  shape.half_extents = 0.5 * obstacle.size;
  const double norm = obstacle.normal.norm();
  shape.normal = norm > 0.0 ? Vec3(obstacle.normal / norm) : Vec3::UnitZ();
  shape.offset = norm > 0.0 ? obstacle.offset / norm : obstacle.offset;
  shape.mesh = obstacle.mesh_data;
  shape.padding = obstacle.padding;
  return shape;
}

Friction toFriction(const FrictionConfig& friction) {
  Friction out;
  out.static_coefficient = friction.static_coefficient;
  out.kinetic_coefficient = friction.kinetic_coefficient;
  return out;
}

Collider makeCollider(const ObstacleConfig& obstacle) {
  if (obstacle.shape == ShapeType::kMesh && !obstacle.mesh_data) {
    throw ConfigError(obstacle.name + ".mesh",
                      "the mesh '" + obstacle.mesh + "' is not loaded (scene_assets.h loadMesh)");
  }
  Collider collider;
  collider.name = obstacle.name;
  collider.shape = makeShape(obstacle);
  collider.pose = obstacle.pose;
  collider.has_friction = obstacle.has_friction;
  collider.friction = toFriction(obstacle.friction);
  return collider;
}

CollisionSettings collisionSettings(const SceneConfig& scene) {
  CollisionSettings settings;
  settings.bounds.enabled = scene.bounds.enabled;
  settings.bounds.min = scene.bounds.min;
  settings.bounds.max = scene.bounds.max;
  settings.friction = toFriction(scene.cloth.friction);
  settings.thickness = scene.cloth.thickness;
  settings.self_collision = scene.cloth.self_collision;
  settings.gravity = scene.solver.gravity;
  settings.simd = scene.solver.simd;
  settings.avx512 = scene.solver.avx512;
  for (const ObstacleConfig& obstacle : scene.obstacles) {
    settings.colliders.push_back(makeCollider(obstacle));
  }
  return settings;
}

}  // namespace pbd_cloth
