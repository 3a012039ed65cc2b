#include "pbd_cloth/sim/grippers.h"

#include "pbd_cloth/sim/live_pose.h"
#include "pbd_cloth/sim/simulation.h"

namespace pbd_cloth {

Pose trajectoryPose(const std::vector<Waypoint>& trajectory, double t) {
  if (t <= trajectory.front().t) return trajectory.front().pose;
  for (std::size_t k = 1; k < trajectory.size(); ++k) {
    const Waypoint &a = trajectory[k - 1], &b = trajectory[k];
    if (t <= b.t) {
      const double span = b.t - a.t;
      return interpolate(a.pose, b.pose, span > 0.0 ? (t - a.t) / span : 1.0);
    }
  }
  return trajectory.back().pose;
}

void Grippers::build(const std::vector<GripperConfig>& configs, int cloth_count) {
  states_.assign(configs.size(), GripperState());
  for (std::size_t g = 0; g < states_.size(); ++g) {
    states_[g].grasped.reserve(cloth_count);
    states_[g].local_offsets.reserve(cloth_count);
    const auto& trajectory = configs[g].trajectory;
    if (!trajectory.empty()) states_[g].pose = states_[g].target = trajectory.front().pose;
  }
}

bool Grippers::setPose(int gripper, const Pose& pose) {
  if (!poseProblem(pose).empty()) return false;
  states_[gripper].live = true;
  states_[gripper].target = pose;
  states_[gripper].target.orientation.normalize();
  return true;
}

// grasped and local_offsets have room for every cloth particle from build().
int Grippers::changeGrasp(int gripper, bool grasp, const GripperConfig& config,
                          Particles& particles, const Particles& initial_particles) {
  GripperState& state = states_[gripper];
  const int released = static_cast<int>(state.grasped.size());
  release(state, particles);
  if (grasp) {
    const Pose& pose = state.pose;
    const Eigen::Quaterniond to_local = pose.orientation.conjugate();
    for (int i = 0; i < particles.cloth_count; ++i) {
      if (initial_particles.isKinematic(i) || particles.isKinematic(i)) continue;  // pinned/held
      if ((particles.position[i] - pose.position).norm() > config.radius) continue;
      state.grasped.push_back(i);
      state.local_offsets.push_back(to_local * (particles.position[i] - pose.position));
      particles.inverse_mass[i] = 0.0;
      particles.kinematic_from[i] = particles.kinematic_to[i] = particles.position[i];
    }
    state.grasping = !state.grasped.empty();
  }
  return grasp ? static_cast<int>(state.grasped.size()) : released;
}

// A released particle keeps the velocity it had in the gripper: the solver gives a held particle
// the velocity of its own prescribed path over the last substep, (x_to - x_from) / dt with
// x = p + R o, i.e. v + (R_to R_from^-1 - I) r / dt = v + omega x r to first order in the step's
// rotation (a chord, as every velocity here). So a gripper that turns while it lets go throws the
// far particles faster than the near ones; the gripper's linear velocity alone would not. Until a
// step has moved it, a particle grasped and released at once keeps its free velocity.
void Grippers::release(GripperState& gripper, Particles& particles) {
  for (int i : gripper.grasped) particles.inverse_mass[i] = 1.0 / particles.mass[i];
  gripper.grasped.clear();
  gripper.local_offsets.clear();
  gripper.grasping = false;
}

void Grippers::moveHeld(Particles& particles, double dt) {
  for (GripperState& state : states_) {
    state.velocity = (state.target.position - state.pose.position) / dt;
    for (std::size_t k = 0; k < state.grasped.size(); ++k) {
      particles.kinematic_to[state.grasped[k]] =
          state.target.position + state.target.orientation * state.local_offsets[k];
    }
  }
}

Eigen::Vector3d Grippers::force(int gripper, const Vec3Array& support_force) const {
  Eigen::Vector3d force = Eigen::Vector3d::Zero();
  for (int i : states_[gripper].grasped) force += support_force[i];
  return force;
}

}  // namespace pbd_cloth
