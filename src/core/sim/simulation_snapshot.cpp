// Simulation::getState / setState: the simulation as a SimulationState (the saved state's
// contents, saved_state.h) and back, with the check that a state fits this scene.
#include <cmath>
#include <set>
#include <sstream>

#include "pbd_cloth/sim/simulation.h"

namespace pbd_cloth {

namespace {

// "field[index]" for the reasons.
std::string at(const std::string& field, std::size_t index) {
  return field + "[" + std::to_string(index) + "]";
}

std::string checkVectors(const std::string& field, const Vec3Array& values) {
  for (std::size_t i = 0; i < values.size(); ++i) {
    if (!values[i].allFinite()) return at(field, i) + ": not finite";
  }
  return std::string();
}

// Stored as given, not normalised (the state continues bit for bit); a quaternion of zero length
// has no rotation at all.
std::string checkPose(const std::string& field, const Pose& pose) {
  if (!pose.position.allFinite()) return field + ".position: not finite";
  if (!pose.orientation.coeffs().allFinite()) return field + ".orientation: not finite";
  if (pose.orientation.norm() < 1e-6) return field + ".orientation: zero length";
  return std::string();
}

std::string checkCount(const std::string& field, std::size_t given, std::size_t scene,
                       const std::string& what) {
  if (given == scene) return std::string();
  std::ostringstream out;
  out << field << ": " << given << " given, the scene has " << scene << ' ' << what;
  return out.str();
}

std::string checkName(const std::string& field, const std::string& given,
                      const std::string& scene) {
  if (given == scene) return std::string();
  return field + ".name: '" + given + "', the scene's is '" + scene + "'";
}

std::string checkBody(const std::string& field, const BodySnapshot& body,
                      const std::string& scene_name) {
  std::string error = checkName(field, body.name, scene_name);
  if (error.empty()) error = checkPose(field + ".pose", body.pose);
  if (error.empty()) error = checkPose(field + ".target", body.target);
  return error;
}

}  // namespace

void Simulation::getState(SimulationState& state) const {
  state.time = time_;
  state.position = particles_.position;
  state.velocity = particles_.velocity;
  state.substep_start = particles_.substep_start;
  state.grippers.resize(grippers_.count());
  for (int g = 0; g < grippers_.count(); ++g) {
    const GripperState& from = grippers_[g];
    GripperSnapshot& to = state.grippers[g];
    to.name = scene_.grippers[g].name;
    to.pose = from.pose;
    to.target = from.target;
    to.live = from.live;
    to.grasped = from.grasped;
    to.grasp_offsets = from.local_offsets;
    to.velocity = from.velocity;
    to.next_waypoint = from.next_waypoint;
  }
  const std::vector<Collider>& colliders = collisions_.obstacles();
  state.colliders.resize(colliders.size());
  for (std::size_t k = 0; k < colliders.size(); ++k) {
    state.colliders[k] = BodySnapshot();
    state.colliders[k].name = colliders[k].name;
    collisions_.getColliderState(static_cast<int>(k), state.colliders[k]);
  }
  state.robot_links.resize(links_.count());
  for (int l = 0; l < links_.count(); ++l) {
    BodySnapshot& to = state.robot_links[l];
    to = BodySnapshot();
    to.name = scene_.robot.model.links[l].name;
    to.pose = links_[l].pose;
    to.target = links_[l].target;
    to.live = links_[l].live;
    to.enabled = links_[l].enabled;
  }
  collisions_.getMeshContacts(state.mesh_contacts);
  state.search_window = collisions_.adaptiveSearchWindow();
  state.chosen_substeps = accuracy_.active() ? accuracy_.substeps() : 0;
  state.calm_steps = accuracy_.active() ? accuracy_.calmSteps() : 0;
  state.rope_orientations.clear();
  state.rope_angular_velocities.clear();
  for (const Rod& rope : ropes_) {
    for (int s = 0; s < rope.segments(); ++s) {
      const Quaternion& q = rope.orientation[s];
      state.rope_orientations.insert(state.rope_orientations.end(), {q.x(), q.y(), q.z(), q.w()});
      state.rope_angular_velocities.push_back(rope.angular_velocity[s]);
    }
  }
}

std::string Simulation::checkState(const SimulationState& state) const {
  if (!std::isfinite(state.time) || state.time < 0.0) {
    return "time: " + std::to_string(state.time) + " is not a finite time >= 0";
  }
  const std::size_t n = particles_.position.size();
  std::string error = checkCount("positions", state.position.size(), n, "particles");
  if (error.empty()) error = checkCount("velocities", state.velocity.size(), n, "particles");
  if (error.empty() && !state.substep_start.empty()) {
    error = checkCount("substep_start", state.substep_start.size(), n, "particles");
  }
  if (error.empty()) error = checkVectors("positions", state.position);
  if (error.empty()) error = checkVectors("velocities", state.velocity);
  if (error.empty()) error = checkVectors("substep_start", state.substep_start);
  if (!error.empty()) return error;

  error = checkCount("grippers", state.grippers.size(), grippers_.count(), "grippers");
  std::set<int> held;
  for (std::size_t g = 0; error.empty() && g < state.grippers.size(); ++g) {
    const GripperSnapshot& gripper = state.grippers[g];
    const std::string field = at("grippers", g);
    error = checkName(field, gripper.name, scene_.grippers[g].name);
    if (error.empty()) error = checkPose(field + ".pose", gripper.pose);
    if (error.empty()) error = checkPose(field + ".target", gripper.target);
    if (error.empty() && !gripper.velocity.allFinite()) error = field + ".velocity: not finite";
    if (error.empty() && !scene_.grippers[g].repeat &&
        gripper.next_waypoint > scene_.grippers[g].trajectory.size()) {
      error = field + ".next_waypoint: " + std::to_string(gripper.next_waypoint) +
              ", the trajectory has " + std::to_string(scene_.grippers[g].trajectory.size()) +
              " waypoints";
    }
    if (error.empty()) {
      error = checkCount(field + ".grasp_offsets", gripper.grasp_offsets.size(),
                         gripper.grasped.size(), "grasped particles in this state");
    }
    if (error.empty()) error = checkVectors(field + ".grasp_offsets", gripper.grasp_offsets);
    for (std::size_t k = 0; error.empty() && k < gripper.grasped.size(); ++k) {
      const int i = gripper.grasped[k];
      const std::string index = at(field + ".grasped", k) + ": particle " + std::to_string(i);
      if (i < 0 || i >= particles_.cloth_count) {
        error = index + " is not a cloth particle (0.." +
                std::to_string(particles_.cloth_count - 1) + ")";
      } else if (initial_particles_.isKinematic(i)) {
        error = index + " is pinned by the scene";
      } else if (!held.insert(i).second) {
        error = index + " is held twice";
      }
    }
  }
  if (!error.empty()) return error;

  const std::vector<Collider>& colliders = collisions_.obstacles();
  error = checkCount("colliders", state.colliders.size(), colliders.size(),
                     "obstacles and robot collision elements");
  for (std::size_t k = 0; error.empty() && k < state.colliders.size(); ++k) {
    error = checkBody(at("colliders", k), state.colliders[k], colliders[k].name);
  }
  if (error.empty()) {
    error = checkCount("robot_links", state.robot_links.size(), links_.count(), "robot links");
  }
  for (std::size_t l = 0; error.empty() && l < state.robot_links.size(); ++l) {
    error = checkBody(at("robot_links", l), state.robot_links[l], scene_.robot.model.links[l].name);
  }
  if (error.empty() && (state.search_window < 0 || state.search_window > kMaxPasses)) {
    error = "search_window: " + std::to_string(state.search_window) + " is not in [0, " +
            std::to_string(kMaxPasses) + "] substeps";
  }
  if (error.empty() && state.calm_steps < 0) {
    error = "calm_steps: " + std::to_string(state.calm_steps) + " is negative";
  }
  if (error.empty() && (state.chosen_substeps < 0 || state.chosen_substeps > kMaxPasses)) {
    error = "chosen_substeps: " + std::to_string(state.chosen_substeps) + " is not in [0, " +
            std::to_string(kMaxPasses) + "]";
  }
  std::size_t segments = 0;
  for (const Rod& rope : ropes_) segments += rope.segments();
  if (error.empty() && (state.rope_orientations.size() != 4 * segments ||
                        state.rope_angular_velocities.size() != segments)) {
    error = "rope_orientations / rope_angular_velocities: " +
            std::to_string(state.rope_orientations.size() / 4) + " / " +
            std::to_string(state.rope_angular_velocities.size()) +
            " segments, the scene's ropes have " + std::to_string(segments);
  }
  for (std::size_t k = 0; error.empty() && k < state.rope_orientations.size(); k += 4) {
    const Eigen::Vector4d q(state.rope_orientations[k], state.rope_orientations[k + 1],
                            state.rope_orientations[k + 2], state.rope_orientations[k + 3]);
    if (!q.allFinite() || std::abs(q.norm() - 1.0) > 1e-6 ||
        !state.rope_angular_velocities[k / 4].allFinite()) {
      error = at("rope_orientations", k / 4) + ": not a finite unit quaternion and velocity";
    }
  }
  for (std::size_t c = 0; error.empty() && c < state.mesh_contacts.size(); ++c) {
    const MeshContactCache& cache = state.mesh_contacts[c];
    const std::string field = at("mesh_contacts", c);
    if (cache.particle < 0 || cache.particle >= static_cast<int>(n)) {
      error = field + ".particle: " + std::to_string(cache.particle) + " is not a particle";
    } else if (cache.collider < 0 || cache.collider >= static_cast<int>(colliders.size()) ||
               colliders[cache.collider].shape.type != ShapeType::kMesh) {
      error = field + ".collider: " + std::to_string(cache.collider) + " is not a mesh collider";
    } else if (!std::isfinite(cache.distance) || !cache.point.allFinite()) {
      error = field + ": not finite";
    }
  }
  return error;
}

bool Simulation::setState(const SimulationState& state, std::string& reason) {
  wake();
  reason = checkState(state);
  if (!reason.empty()) return false;

  time_ = state.time;
  solver_.mutableStats().sim_time = state.time;
  particles_.position = state.position;
  particles_.velocity = state.velocity;
  particles_.substep_start = state.substep_start.empty() ? state.position : state.substep_start;
  particles_.step_start = state.position;
  particles_.kinematic_from = state.position;
  particles_.kinematic_to = state.position;
  particles_.inverse_mass = initial_particles_.inverse_mass;
  for (int g = 0; g < grippers_.count(); ++g) {
    const GripperSnapshot& from = state.grippers[g];
    GripperState& to = grippers_[g];
    to.pose = from.pose;
    to.target = from.target;
    to.live = from.live;
    to.grasped = from.grasped;
    to.local_offsets = from.grasp_offsets;
    to.grasping = !from.grasped.empty();
    to.velocity = from.velocity;
    to.next_waypoint = from.next_waypoint;
    for (int i : to.grasped) particles_.inverse_mass[i] = 0.0;
  }
  for (std::size_t k = 0; k < state.colliders.size(); ++k) {
    collisions_.setColliderState(static_cast<int>(k), state.colliders[k]);
  }
  for (int l = 0; l < links_.count(); ++l) {
    const BodySnapshot& from = state.robot_links[l];
    links_[l].pose = from.pose;
    links_[l].target = from.target;
    links_[l].live = from.live;
    links_[l].enabled = from.enabled;
  }
  std::size_t segment = 0;
  for (Rod& rope : ropes_) {
    for (int s = 0; s < rope.segments(); ++s, ++segment) {
      const double* q = &state.rope_orientations[4 * segment];
      rope.orientation[s] = Quaternion(q[3], q[0], q[1], q[2]);
      rope.orientation_start[s] = rope.orientation[s];
      rope.angular_velocity[s] = state.rope_angular_velocities[segment];
    }
  }
  collisions_.setMeshContacts(state.mesh_contacts);
  collisions_.setAdaptiveSearchWindow(state.search_window);
  if (state.chosen_substeps > 0) accuracy_.restore(state.chosen_substeps, state.calm_steps);
  kinematicSetChanged();  // tethers of the restored grasps
  collisions_.findCandidatesNow(particles_, topology_);
  state_measured_ = false;
  return true;
}

}  // namespace pbd_cloth
