// The runtime colliders made from the scene's description, once: the obstacles' and robot links'
// ObstacleConfig (config/) becomes a geometry Shape (geometry/shapes.h).
#pragma once

#include "pbd_cloth/config/scene_config.h"
#include "pbd_cloth/geometry/shapes.h"

namespace pbd_cloth {

// Builds the local shape of an obstacle. The plane's normal is normalised together with its offset
// so that n.p - offset stays the same plane and becomes a true (1-Lipschitz) distance.
Shape makeShape(const ObstacleConfig& obstacle);

}  // namespace pbd_cloth
