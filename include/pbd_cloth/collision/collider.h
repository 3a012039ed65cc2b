// The runtime's colliders and contact settings, made from the scene description once
// (sim/colliders.h): the collisions keep no configuration of their own.
#pragma once

#include <string>
#include <vector>

#include "pbd_cloth/collision/contact.h"
#include "pbd_cloth/geometry/pose.h"
#include "pbd_cloth/geometry/shapes.h"
#include "pbd_cloth/geometry/vector_types.h"

namespace pbd_cloth {

// A rigid body the particles collide with: a scene obstacle or a robot link's collision element.
struct Collider {
  std::string name;  // the obstacle's, or "<link>/<index>"
  Shape shape;       // in its own frame, grown by its padding
  Pose pose;         // in the scene frame, at the end of the last step
  // Friction of contacts with this shape; the cloth's (CollisionSettings::friction) when not set.
  bool has_friction = false;
  Friction friction;
};

// A box the particles are kept inside (the seed's C1).
struct ParticleBounds {
  bool enabled = false;
  Vec3 min = Vec3::Constant(-10.0);
  Vec3 max = Vec3::Constant(10.0);
};

// What Collisions::configure reads.
struct CollisionSettings {
  ParticleBounds bounds;
  Friction friction;                     // of every collider without its own, and between particles
  double thickness = 0.005;              // cloth contact radius (m)
  bool self_collision = false;           // cloth against itself
  Vec3 gravity = Vec3(0.0, 0.0, -9.81);  // for the motion bounds (m/s^2)
  bool simd = true;    // the path boxes' kernel (path_boxes.h): AVX2 where available ...
  bool avx512 = true;  // ... and AVX-512
  std::vector<Collider> colliders;  // the scene's obstacles
};

}  // namespace pbd_cloth
