// The grippers of a scene: where each is and is going, what it holds and at which offsets, the
// scripted trajectory it follows until a live pose takes over, and the force its hold feels.
// Simulation owns them and drives them through the step; grasps that change the kinematic set go
// through Simulation, which rebuilds the tethers and wakes the scene after them.
#pragma once

#include <cstddef>
#include <vector>

#include "pbd_cloth/config/scene_config.h"
#include "pbd_cloth/model/particles.h"

namespace pbd_cloth {

// Pose of a scripted trajectory at time t: linear/slerp between waypoints, held after the last.
Pose trajectoryPose(const std::vector<Waypoint>& trajectory, double t);

struct GripperState {
  Pose pose;          // pose at the end of the last step
  Pose target;        // pose at the end of the next step
  bool live = false;  // a pose message arrived: the trajectory is no longer followed
  bool grasping = false;
  std::vector<int> grasped;                    // particle indices
  std::vector<Eigen::Vector3d> local_offsets;  // grasped particle positions in the gripper frame
  // Linear velocity over the last step (reported in the state; released particles keep their
  // own velocity, which includes the gripper's rotation: release).
  Eigen::Vector3d velocity = Eigen::Vector3d::Zero();
  std::size_t next_waypoint = 0;  // first waypoint whose grasp event is pending
};

class Grippers {
 public:
  // One gripper per config, nothing held, at the start of its trajectory. Room for every cloth
  // particle in each hold (28 bytes each), so a grasp inside the step never allocates.
  void build(const std::vector<GripperConfig>& configs, int cloth_count);

  int count() const { return static_cast<int>(states_.size()); }
  const GripperState& operator[](int gripper) const { return states_[gripper]; }
  GripperState& operator[](int gripper) { return states_[gripper]; }
  const Pose& pose(int gripper) const { return states_[gripper].pose; }
  bool grasping(int gripper) const { return states_[gripper].grasping; }

  // The pose the gripper reaches at the end of the next step; it stops following its trajectory.
  // A pose with a poseProblem() is refused (false).
  bool setPose(int gripper, const Pose& pose);

  // Grasp: every free cloth particle within the radius becomes kinematic, held at its offset in
  // the gripper frame; release: they are free again. Returns how many were grasped (released).
  // Composes no message, so the scripted events inside the step allocate nothing.
  int changeGrasp(int gripper, bool grasp, const GripperConfig& config, Particles& particles,
                  const Particles& initial_particles);

  // Each gripper's linear velocity over the step, and where its held particles are at its end.
  void moveHeld(Particles& particles, double dt);
  // The step is done: each gripper is where it was going.
  void endStep() {
    for (GripperState& state : states_) state.pose = state.target;
  }

  // Force (N) the held particles exerted on the gripper over the last step (simulation.h).
  Eigen::Vector3d force(int gripper, const Vec3Array& support_force) const;

 private:
  void release(GripperState& gripper, Particles& particles);

  std::vector<GripperState> states_;
};

}  // namespace pbd_cloth
