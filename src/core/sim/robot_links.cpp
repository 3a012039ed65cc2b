#include "pbd_cloth/sim/robot_links.h"

#include <algorithm>
#include <string>

#include "pbd_cloth/sim/colliders.h"
#include "pbd_cloth/sim/live_pose.h"

namespace pbd_cloth {

void RobotLinks::readTrajectory(const RobotConfig& robot) {
  const std::size_t joint_count = robot.model.joints.size();
  std::vector<double> previous(joint_count, 0.0);
  joint_waypoints_.clear();
  for (std::size_t w = 0; w < robot.joint_trajectory.size(); ++w) {
    for (const auto& entry : robot.joint_trajectory[w].positions) {
      const int joint = robot.model.jointIndex(entry.first);
      if (joint < 0) {
        throw ConfigError(
            "robot.joint_trajectory[" + std::to_string(w) + "].positions." + entry.first,
            "no joint '" + entry.first + "' in the URDF");
      }
      previous[joint] = entry.second;
    }
    joint_waypoints_.push_back(previous);
  }
  joint_positions_.assign(joint_count, 0.0);
  link_poses_.reserve(robot.model.links.size());
}

void RobotLinks::build(const RobotConfig& robot, Collisions& collisions) {
  const RobotModel& model = robot.model;
  links_.assign(model.links.size(), RobotLinkState());
  if (model.links.empty()) return;
  followJointTrajectory(robot, 0.0);
  for (std::size_t l = 0; l < model.links.size(); ++l) {
    RobotLinkState& link = links_[l];
    link.pose = link.target;
    link.first_collider = static_cast<int>(collisions.obstacles().size());
    for (const ObstacleConfig& element : model.links[l].collisions) {
      ObstacleConfig collider = element;
      collider.pose = link.pose.compose(element.pose);
      collisions.addCollider(makeCollider(collider));
      ++link.collider_count;
    }
  }
}

void RobotLinks::followJointTrajectory(const RobotConfig& robot, double t) {
  if (links_.empty()) return;
  const std::size_t count = joint_waypoints_.size();
  if (count == 0) {
    std::fill(joint_positions_.begin(), joint_positions_.end(), 0.0);
  } else if (t <= robot.joint_trajectory.front().t) {
    joint_positions_ = joint_waypoints_.front();
  } else if (t >= robot.joint_trajectory.back().t) {
    joint_positions_ = joint_waypoints_.back();
  } else {
    std::size_t k = 1;
    while (robot.joint_trajectory[k].t < t) ++k;
    const double t0 = robot.joint_trajectory[k - 1].t, t1 = robot.joint_trajectory[k].t;
    const double s = t1 > t0 ? (t - t0) / (t1 - t0) : 1.0;
    for (std::size_t j = 0; j < joint_positions_.size(); ++j) {
      joint_positions_[j] = (1.0 - s) * joint_waypoints_[k - 1][j] + s * joint_waypoints_[k][j];
    }
  }
  robot.model.linkPoses(robot.pose, joint_positions_, link_poses_);
  for (std::size_t l = 0; l < links_.size(); ++l) {
    if (!links_[l].live) links_[l].target = link_poses_[l];
  }
}

void RobotLinks::moveColliders(const RobotModel& model, Collisions& collisions) const {
  for (std::size_t l = 0; l < links_.size(); ++l) {
    const RobotLinkState& link = links_[l];
    for (int e = 0; e < link.collider_count; ++e) {
      collisions.setObstacleTarget(link.first_collider + e,
                                   link.target.compose(model.links[l].collisions[e].pose));
    }
  }
}

bool RobotLinks::setPose(int link, const Pose& pose) {
  if (!poseProblem(pose).empty()) return false;
  links_[link].live = true;
  links_[link].target = pose;
  links_[link].target.orientation.normalize();
  return true;
}

void RobotLinks::setEnabled(int link, bool enabled, Collisions& collisions) {
  RobotLinkState& state = links_[link];
  if (enabled && !state.enabled) state.pose = state.target;  // no sweep from where it was lost
  state.enabled = enabled;
  for (int e = 0; e < state.collider_count; ++e) {
    collisions.setObstacleEnabled(state.first_collider + e, enabled);
  }
}

}  // namespace pbd_cloth
