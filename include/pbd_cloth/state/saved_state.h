// A snapshot of everything a Simulation carries from one step to the next, so a run can be saved
// and continued bit for bit (Simulation::getState / setState; cloth_bench --save-state and
// --load-state; the node's ~get_state and ~set_state), and its binary file format.
//
// What is carried and why:
// - time, positions, velocities: the state proper (Verlet's velocity is its half-step velocity).
// - substep_start: the positions at the start of the last substep; the particle-particle contact
//   falls back on it for the direction between two coincident particles at the next step start.
// - grippers: pose, target, whether a live pose drives them, the particles they hold with their
//   offsets in the gripper frame, their velocity over the last step (reported; a released particle
//   keeps its own velocity, carried among the particles' velocities) and the next waypoint whose
//   grasp event is pending.
// - colliders (the scene's obstacles, then each robot link's collision elements, "<link>/<k>"):
//   pose, target, enabled, and whether they jump to their next target (enabled again).
// - robot_links: pose, target, live (off robot.joint_trajectory), enabled.
// - mesh_contacts: per (particle, mesh collider) the closest triangle of the last query and the
//   distance and place of it. The triangle is the search's first guess and decides between
//   equally near triangles; the distance bounds the next one (collisions.cpp).
// - search_window: the contact search window the adaptive rule chose for the next step (substeps;
//   Collisions, "The search window"); it shapes the next step's candidates and so its result. Only
//   the pairs that were ever queried are listed.
// What is not carried, because the step rebuilds it before using it: kinematic targets, contact
// candidates and their friction windows (found anew every step), XPBD multipliers (zero at every
// substep), tethers (rebuilt from the kinematic set), inverse masses (the scene's, zero for held
// particles). Scene settings (solver, compliance, friction) belong to the scene, not the state.
#pragma once

#include <cstddef>
#include <cstdint>
#include <iosfwd>
#include <string>
#include <vector>

#include "pbd_cloth/collision/collider_snapshot.h"
#include "pbd_cloth/geometry/pose.h"
#include "pbd_cloth/model/particles.h"

namespace pbd_cloth {

struct GripperSnapshot {
  std::string name;
  Pose pose;                 // at the state's time
  Pose target;               // where the next step takes it
  bool live = false;         // driven by poses given (setGripperPose), no longer by its trajectory
  std::vector<int> grasped;  // particle indices held (empty: open)
  Vec3Array grasp_offsets;   // their positions in the gripper frame, one per grasped index
  Vec3 velocity = Vec3::Zero();   // m/s over the last step
  std::size_t next_waypoint = 0;  // first trajectory waypoint whose grasp event is pending
};

struct SimulationState {
  double time = 0.0;  // s of simulated time
  Vec3Array position;
  Vec3Array velocity;
  Vec3Array substep_start;
  std::vector<GripperSnapshot> grippers;  // one per scene gripper, in scene order
  std::vector<BodySnapshot> colliders;    // scene obstacles, then robot collision elements
  std::vector<BodySnapshot> robot_links;  // one per URDF link
  std::vector<MeshContactCache> mesh_contacts;
  int search_window = 0;  // substeps; 0: none chosen yet (the whole step)
  // The substeps solver.target_max_strain chose for the next step (accuracy_controller.h); 0:
  // no target, or none chosen yet.
  int chosen_substeps = 0;
  int calm_steps = 0;  // the controller's count of steps well under the target (the same header)
  // The ropes' segments (model/rod.h), every rope's in scene order: orientation (x y z w) and
  // angular velocity (rad/s, world frame). Empty: no ropes.
  std::vector<double> rope_orientations;  // 4 per segment
  Vec3Array rope_angular_velocities;
};

// The state file: "PBDSTATE", a format version (uint32), then the fields in the order of
// SimulationState, every number in the machine's own binary (IEEE doubles, little-endian on every
// platform ROS supports): nothing is rounded, so a state read back is the state written.
// Version 2 added search_window at the end, version 3 chosen_substeps and calm_steps after it,
// version 4 the ropes' segments after those; older files still read (those fields 0 or empty).
constexpr std::uint32_t kStateFileVersion = 4;
constexpr std::uint32_t kOldestStateFileVersion = 1;
void writeState(std::ostream& out, const SimulationState& state);
// False with the reason (wrong magic or version, truncated, implausible sizes) on a bad file;
// whether the state fits a scene is Simulation::setState's question.
bool readState(std::istream& in, SimulationState& state, std::string& reason);
bool writeStateFile(const std::string& path, const SimulationState& state, std::string& reason);
bool readStateFile(const std::string& path, SimulationState& state, std::string& reason);

// The part of the state a ROS message does not spell out field by field (substep_start,
// mesh_contacts and search_window), in the same binary form: the messages' `solver_data`.
std::vector<std::uint8_t> encodeSolverData(const SimulationState& state);
bool decodeSolverData(const std::vector<std::uint8_t>& data, SimulationState& state,
                      std::string& reason);

}  // namespace pbd_cloth
