// Forward kinematics of the URDF's joint tree: a link's pose is its parent's pose composed with its
// parent joint's origin and motion. Called every step, so it allocates nothing once `out` has its
// size, and it does not rely on the link order: each link walks up its own chain to the root
// (n links x depth compositions: a few dozen for an arm, cheaper than keeping a visit order).
#include "pbd_cloth/config/robot_model.h"

#include <Eigen/Geometry>
#include <stdexcept>

namespace pbd_cloth {
namespace {

// The position of joint `j`: its own, or for a mimic joint multiplier * mimicked + offset (URDF's
// <mimic>), following chains of mimic joints. Missing entries of `positions` read as 0.
double jointPosition(const std::vector<RobotJoint>& joints, const std::vector<double>& positions,
                     int j) {
  double multiplier = 1.0;
  double offset = 0.0;
  // A mimic chain longer than the joint count is a cycle.
  for (std::size_t hops = 0; joints[j].mimic_joint >= 0; ++hops) {
    if (hops >= joints.size()) throw std::logic_error("RobotModel: cycle of mimic joints");
    offset += multiplier * joints[j].mimic_offset;
    multiplier *= joints[j].mimic_multiplier;
    j = joints[j].mimic_joint;
  }
  const double own = static_cast<std::size_t>(j) < positions.size() ? positions[j] : 0.0;
  return multiplier * own + offset;
}

// The child link frame in the parent link frame: origin, then the joint's motion along its axis.
Pose jointTransform(const RobotJoint& joint, double position) {
  Pose motion;
  switch (joint.type) {
    case JointType::kRevolute:
    case JointType::kContinuous:
      motion.orientation = Eigen::Quaterniond(Eigen::AngleAxisd(position, joint.axis));
      break;
    case JointType::kPrismatic:
      motion.position = position * joint.axis;
      break;
    case JointType::kFixed:
    case JointType::kFloating:  // no state in the URDF: held at the origin
    case JointType::kPlanar:
      break;
  }
  return joint.origin.compose(motion);
}

}  // namespace

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

void RobotModel::linkPoses(const Pose& root_pose, const std::vector<double>& joint_positions,
                           std::vector<Pose>& out) const {
  out.resize(links.size());
  const int joint_count = static_cast<int>(joints.size());
  for (std::size_t k = 0; k < links.size(); ++k) {
    // The link in the root link's frame, built from the link upwards: each parent joint's
    // transform is applied on the left of what is below it.
    Pose in_root;
    int link = static_cast<int>(k);
    for (std::size_t depth = 0;; ++depth) {
      const int j = links[link].parent_joint;
      if (j < 0 || j >= joint_count) break;
      if (depth >= links.size()) throw std::logic_error("RobotModel: cycle in the joint tree");
      in_root =
          jointTransform(joints[j], jointPosition(joints, joint_positions, j)).compose(in_root);
      link = joints[j].parent_link;
      if (link < 0 || link >= static_cast<int>(links.size())) break;
    }
    out[k] = root_pose.compose(in_root);
  }
}

}  // namespace pbd_cloth
