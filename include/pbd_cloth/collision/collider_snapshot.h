// What a saved state (state/saved_state.h) keeps of a collider, and of a robot link, between two
// steps: the body's pose, target and flags, and the mesh colliders' per-contact search caches.
// Declared here, beside the collisions that fill and read them, so that the collisions need not
// know the save format.
#pragma once

#include <string>

#include "pbd_cloth/geometry/pose.h"
#include "pbd_cloth/geometry/vector_types.h"

namespace pbd_cloth {

// A collider (obstacle or robot link collision element) or a robot link.
struct BodySnapshot {
  std::string name;
  Pose pose;    // at the state's time
  Pose target;  // where the next step takes it
  bool enabled = true;
  bool live = false;            // robot links: posed by input, no longer by joint_trajectory
  bool jump_to_target = false;  // colliders: enabled again, placed at the next target unswept
};

struct MeshContactCache {
  int particle = 0;
  int collider = 0;
  int triangle = -1;      // closest triangle of the last query
  double distance = 0.0;  // the distance found (m), and where (collider frame)
  Vec3 point = Vec3::Zero();
};

}  // namespace pbd_cloth
