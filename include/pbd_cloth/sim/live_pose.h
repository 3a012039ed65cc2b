// The check every pose from outside passes before it moves a gripper, an obstacle or a robot link.
#pragma once

#include <string>

#include "pbd_cloth/config/scene_config.h"

namespace pbd_cloth {

// Live poses (grippers, obstacles, robot links) farther than this from the scene origin in any
// coordinate are refused: nothing a robot handles is 10 km away, and an absurd coordinate (1e300
// from a corrupted message) would overflow the step's squares into Inf and NaN.
constexpr double kMaxPoseCoordinate = 1e4;  // m

// Whether a live pose may enter the simulation: a finite position within kMaxPoseCoordinate, a
// finite orientation of non-zero length. Empty when it may, else why not.
std::string poseProblem(const Pose& pose);

}  // namespace pbd_cloth
