// The robot's URDF as the scene describes it (robot.urdf_file or the node's robot_description):
// links with their collision elements and the joint tree, filled by the scene reader
// (scene_assets.h), checked by validate() and posed by forward kinematics (robot_model.cpp).
#pragma once

#include <Eigen/Core>
#include <string>
#include <vector>

#include "pbd_cloth/config/obstacle_config.h"
#include "pbd_cloth/geometry/pose.h"

namespace pbd_cloth {

enum class JointType { kFixed, kRevolute, kContinuous, kPrismatic, kFloating, kPlanar };

// A joint of the URDF's kinematic tree (floating and planar joints are held at their origin).
struct RobotJoint {
  std::string name;
  JointType type = JointType::kFixed;
  int parent_link = -1;  // index into RobotModel::links
  int child_link = -1;
  Pose origin;                          // child joint frame in the parent link frame at position 0
  Eigen::Vector3d axis{1.0, 0.0, 0.0};  // unit, in the joint frame
  double lower = 0.0, upper = 0.0;      // limits (revolute, prismatic); not enforced by FK
  int mimic_joint = -1;                 // position = multiplier * mimicked + offset
  double mimic_multiplier = 1.0, mimic_offset = 0.0;
};

struct RobotLink {
  std::string name;
  // Every <collision> element of the link, in file order; pose = its origin in the link frame.
  std::vector<ObstacleConfig> collisions;
  int parent_joint = -1;  // -1 for the root link
};

// The URDF as the simulation needs it: links with their collision shapes and the joint tree.
// Filled by the scene reader (scene_assets.h); forward kinematics in robot_model.cpp.
struct RobotModel {
  std::string name;
  std::vector<RobotLink> links;
  std::vector<RobotJoint> joints;
  int root_link = -1;

  int linkIndex(const std::string& link) const;    // -1 when absent
  int jointIndex(const std::string& joint) const;  // -1 when absent
  // Pose of every link in the scene frame with the root link at `root_pose`, for joint positions
  // indexed like `joints` (fixed joints ignore theirs; mimic joints follow their joint). `out` is
  // resized to links.size().
  void linkPoses(const Pose& root_pose, const std::vector<double>& joint_positions,
                 std::vector<Pose>& out) const;
};

}  // namespace pbd_cloth
