// The robot's links as kinematic bodies: each link's collision elements are colliders of the
// scene (after the obstacles), posed by forward kinematics of robot.joint_trajectory until a live
// pose (the node's tf) takes the link over. Simulation owns them and moves them in the step.
#pragma once

#include <vector>

#include "pbd_cloth/collision/collisions.h"
#include "pbd_cloth/config/scene_config.h"

namespace pbd_cloth {

// A robot link: its colliders [first_collider, first_collider + collider_count) in Collisions.
struct RobotLinkState {
  int first_collider = 0;
  int collider_count = 0;
  Pose pose;          // at the end of the last step
  Pose target;        // at the end of the next step
  bool live = false;  // a pose was given: robot.joint_trajectory no longer poses it
  bool enabled = true;
};

class RobotLinks {
 public:
  // Every waypoint of robot.joint_trajectory as a full vector of joint positions (a joint a
  // waypoint does not name keeps its previous value; 0 before the first), so the step only
  // interpolates. Throws ConfigError on a joint the URDF does not have.
  void readTrajectory(const RobotConfig& robot);
  // The links' collision elements become colliders after the obstacles, posed at the start of
  // robot.joint_trajectory (all joints at 0 without one).
  void build(const RobotConfig& robot, Collisions& collisions);

  int count() const { return static_cast<int>(links_.size()); }
  const RobotLinkState& operator[](int link) const { return links_[link]; }
  RobotLinkState& operator[](int link) { return links_[link]; }
  bool hasCollision(int link) const { return links_[link].collider_count > 0; }
  const Pose& pose(int link) const { return links_[link].pose; }
  bool enabled(int link) const { return links_[link].enabled; }

  // The pose the link reaches at the end of the next step; it leaves the joint trajectory. A
  // pose with a poseProblem() is refused (false).
  bool setPose(int link, const Pose& pose);
  // A disabled link's colliders do not collide; enabled again, it starts at its next pose.
  void setEnabled(int link, bool enabled, Collisions& collisions);

  // Targets of the links that no live pose drives: forward kinematics of the joint trajectory at
  // t. Allocates nothing (scratch sized in readTrajectory).
  void followJointTrajectory(const RobotConfig& robot, double t);
  // Every collision element follows its link: element pose = link target composed with its origin.
  void moveColliders(const RobotModel& model, Collisions& collisions) const;
  // The step is done: each link is where it was going.
  void endStep() {
    for (RobotLinkState& link : links_) link.pose = link.target;
  }

 private:
  std::vector<RobotLinkState> links_;  // one per robot.model.links
  std::vector<std::vector<double>> joint_waypoints_;
  // Scratch for the step.
  std::vector<double> joint_positions_;
  std::vector<Pose> link_poses_;
};

}  // namespace pbd_cloth
