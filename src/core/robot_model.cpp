// Forward kinematics of the URDF's joint tree: each link's pose is its parent's pose, composed with
// the joint's origin and the joint's own motion (rotation about or translation along its axis).
#include <Eigen/Geometry>
#include <cmath>
#include <limits>

#include "pbd_cloth/scene_config.h"

namespace pbd_cloth {

int RobotModel::linkIndex(const std::string& link) const {
  for (std::size_t k = 0; k < links.size(); ++k) {
    if (links[k].name == link) return static_cast<int>(k);
  }
  return -1;
}

int RobotModel::jointIndex(const std::string& joint) const {
  for (std::size_t k = 0; k < joints.size(); ++k) {
    if (joints[k].name == joint) return static_cast<int>(k);
  }
  return -1;
}

namespace {

// The joint's motion at position q, in the joint frame.
Pose jointMotion(const RobotJoint& joint, double q) {
  Pose motion;
  switch (joint.type) {
    case JointType::kRevolute:
    case JointType::kContinuous:
      motion.orientation = Eigen::Quaterniond(Eigen::AngleAxisd(q, joint.axis));
      break;
    case JointType::kPrismatic:
      motion.position = q * joint.axis;
      break;
    case JointType::kFixed:
    case JointType::kFloating:  // held at the origin: the URDF gives them no single axis to follow
    case JointType::kPlanar:
      break;
  }
  return motion;
}

}  // namespace

// Links are posed in tree order from the root: a link is posed once its parent is. URDF trees are
// shallow, so repeated sweeps over the joints (no recursion, no allocation) cost little.
void RobotModel::linkPoses(const Pose& root_pose, const std::vector<double>& joint_positions,
                           std::vector<Pose>& out) const {
  out.resize(links.size());
  if (links.empty()) return;
  // Mark every link unposed with a NaN, then pose the root and sweep until nothing changes.
  for (Pose& pose : out) pose.position.x() = std::numeric_limits<double>::quiet_NaN();
  if (root_link >= 0) out[root_link] = root_pose;
  bool changed = true;
  while (changed) {
    changed = false;
    for (const RobotJoint& joint : joints) {
      if (joint.parent_link < 0 || joint.child_link < 0) continue;
      const Pose& parent = out[joint.parent_link];
      if (std::isnan(parent.position.x()) || !std::isnan(out[joint.child_link].position.x())) {
        continue;
      }
      const std::size_t index = static_cast<std::size_t>(&joint - joints.data());
      double q = index < joint_positions.size() ? joint_positions[index] : 0.0;
      if (joint.mimic_joint >= 0) {
        const double mimicked = static_cast<std::size_t>(joint.mimic_joint) < joint_positions.size()
                                    ? joint_positions[joint.mimic_joint]
                                    : 0.0;
        q = joint.mimic_multiplier * mimicked + joint.mimic_offset;
      }
      out[joint.child_link] = parent.compose(joint.origin).compose(jointMotion(joint, q));
      changed = true;
    }
  }
  // Links outside the root's tree (a malformed model) stay where the root is.
  for (Pose& pose : out) {
    if (std::isnan(pose.position.x())) pose = root_pose;
  }
}

}  // namespace pbd_cloth
