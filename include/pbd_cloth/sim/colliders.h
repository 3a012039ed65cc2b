// The runtime colliders made from the scene's description, once: the obstacles' and robot links'
// ObstacleConfig (config/) becomes a Collider (collision/collider.h) around a geometry Shape
// (geometry/shapes.h), and the scene's contact settings the collisions' CollisionSettings.
#pragma once

#include "pbd_cloth/collision/collider.h"
#include "pbd_cloth/config/scene_config.h"
#include "pbd_cloth/geometry/shapes.h"

namespace pbd_cloth {

// Builds the local shape of an obstacle. The plane's normal is normalised together with its offset
// so that n.p - offset stays the same plane and becomes a true (1-Lipschitz) distance.
Shape makeShape(const ObstacleConfig& obstacle);

Friction toFriction(const FrictionConfig& friction);

// The collider of an obstacle or robot collision element (its shape, pose and friction). Throws
// ConfigError for a mesh shape whose mesh is not loaded.
Collider makeCollider(const ObstacleConfig& obstacle);

// Bounds, cloth friction, thickness and self-collision, gravity, the path-box kernel's switches
// (solver.simd, solver.avx512) and the scene's obstacles as colliders.
CollisionSettings collisionSettings(const SceneConfig& scene);

}  // namespace pbd_cloth
