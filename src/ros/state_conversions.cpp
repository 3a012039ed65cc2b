#include "pbd_cloth/ros/state_conversions.h"

#include "pbd_cloth/ros/ros_conversions.h"

namespace pbd_cloth {

namespace {

// The same conversions as the rest of the adapter: they copy doubles exactly, and poses are not
// normalised on the way out.
geometry_msgs::Point toPoint(const Vec3& v) { return RosConversions::toPoint(v); }
geometry_msgs::Vector3 toVector(const Vec3& v) { return RosConversions::toVector3(v); }
geometry_msgs::Pose toPose(const Pose& pose) { return RosConversions::toPoseMessage(pose); }

template <class Message>
Vec3 toVec3(const Message& m) {
  return Vec3(m.x, m.y, m.z);
}

// Not normalised (RosConversions::fromPoseMessage does): the state continues bit for bit.
Pose fromPose(const geometry_msgs::Pose& msg) {
  Pose pose;
  pose.position = toVec3(msg.position);
  pose.orientation = Eigen::Quaterniond(msg.orientation.w, msg.orientation.x, msg.orientation.y,
                                        msg.orientation.z);
  return pose;
}

SimBody toBody(const BodySnapshot& body) {
  SimBody msg;
  msg.name = body.name;
  msg.pose = toPose(body.pose);
  msg.target = toPose(body.target);
  msg.enabled = body.enabled;
  msg.live = body.live;
  msg.jump_to_target = body.jump_to_target;
  return msg;
}

BodySnapshot fromBody(const SimBody& msg) {
  BodySnapshot body;
  body.name = msg.name;
  body.pose = fromPose(msg.pose);
  body.target = fromPose(msg.target);
  body.enabled = msg.enabled;
  body.live = msg.live;
  body.jump_to_target = msg.jump_to_target;
  return body;
}

}  // namespace

void StateConversions::toMessage(const SimulationState& state, SimState& msg) {
  msg.sim_time = state.time;
  msg.positions.resize(state.position.size());
  for (std::size_t i = 0; i < state.position.size(); ++i) {
    msg.positions[i] = toPoint(state.position[i]);
  }
  msg.velocities.resize(state.velocity.size());
  for (std::size_t i = 0; i < state.velocity.size(); ++i) {
    msg.velocities[i] = toVector(state.velocity[i]);
  }
  msg.grippers.resize(state.grippers.size());
  for (std::size_t g = 0; g < state.grippers.size(); ++g) {
    const GripperSnapshot& from = state.grippers[g];
    SimGripper& to = msg.grippers[g];
    to.name = from.name;
    to.pose = toPose(from.pose);
    to.target = toPose(from.target);
    to.live = from.live;
    to.grasped.assign(from.grasped.begin(), from.grasped.end());
    to.grasp_offsets.resize(from.grasp_offsets.size());
    for (std::size_t k = 0; k < from.grasp_offsets.size(); ++k) {
      to.grasp_offsets[k] = toPoint(from.grasp_offsets[k]);
    }
    to.velocity = toVector(from.velocity);
    to.next_waypoint = static_cast<std::uint32_t>(from.next_waypoint);
  }
  msg.obstacles.clear();
  for (const BodySnapshot& body : state.colliders) msg.obstacles.push_back(toBody(body));
  msg.robot_links.clear();
  for (const BodySnapshot& body : state.robot_links) msg.robot_links.push_back(toBody(body));
  msg.solver_data = encodeSolverData(state);
}

bool StateConversions::fromMessage(const SimState& msg, SimulationState& state,
                                   std::string& reason) {
  SimulationState out;
  if (!msg.solver_data.empty() && !decodeSolverData(msg.solver_data, out, reason)) return false;
  out.time = msg.sim_time;
  for (const auto& p : msg.positions) out.position.push_back(toVec3(p));
  for (const auto& v : msg.velocities) out.velocity.push_back(toVec3(v));
  for (const SimGripper& from : msg.grippers) {
    GripperSnapshot to;
    to.name = from.name;
    to.pose = fromPose(from.pose);
    to.target = fromPose(from.target);
    to.live = from.live;
    // An index beyond int range becomes negative and is refused by setState as no particle.
    for (std::uint32_t i : from.grasped) to.grasped.push_back(static_cast<int>(i));
    for (const auto& p : from.grasp_offsets) to.grasp_offsets.push_back(toVec3(p));
    to.velocity = toVec3(from.velocity);
    to.next_waypoint = from.next_waypoint;
    out.grippers.push_back(to);
  }
  for (const SimBody& body : msg.obstacles) out.colliders.push_back(fromBody(body));
  for (const SimBody& body : msg.robot_links) out.robot_links.push_back(fromBody(body));
  state = std::move(out);
  return true;
}

}  // namespace pbd_cloth
