#include "pbd_cloth/sim/live_pose.h"

namespace pbd_cloth {

std::string poseProblem(const Pose& pose) {
  if (!pose.position.allFinite() || !pose.orientation.coeffs().allFinite()) {
    return "not finite";
  }
  if (pose.position.cwiseAbs().maxCoeff() > kMaxPoseCoordinate) {
    return "position more than " + std::to_string(static_cast<int>(kMaxPoseCoordinate)) +
           " m from the scene origin";
  }
  // The node refuses near-zero quaternions before they get here; this is the core's own guard.
  if (!(pose.orientation.norm() > 1e-12)) return "orientation of zero length";
  return std::string();
}

}  // namespace pbd_cloth
