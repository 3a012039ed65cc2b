// A whole scene in motion: the particles and constraints built from a SceneConfig, the solver, the
// grippers (scripted trajectory or live poses, grasp and release) and the obstacles. ROS-free: the
// node and cloth_bench both drive this class, so a scene replays offline exactly as in the node.
#pragma once

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "pbd_cloth/sim/colliders.h"
#include "pbd_cloth/sim/metrics.h"
#include "pbd_cloth/model/particles.h"
#include "pbd_cloth/config/scene_config.h"
#include "pbd_cloth/state/saved_state.h"
#include "pbd_cloth/solver/solver.h"
#include "pbd_cloth/constraints/taut_chains.h"
#include "pbd_cloth/constraints/tethers.h"

namespace pbd_cloth {

// A step whose result could not stand (Simulation::step, fault recovery).
struct StepFault {
  enum class Kind {
    kNone,
    kNonFinite,  // a particle's position or velocity is NaN or Inf
    kTooFast,    // a free particle moves faster than solver.max_speed: an energy blow-up
  };
  Kind kind = Kind::kNone;
  int particle = -1;   // the first particle found at fault
  double speed = 0.0;  // its speed (m/s), kTooFast
  double time = 0.0;   // simulated time at the end of the step that was undone (s)
};

// "particle 12 not finite" / "particle 12 at 1.3e+04 m/s (solver.max_speed 100 m/s)".
std::string describe(const StepFault& fault, double max_speed);

// Faults a test can inject inside the next step (Simulation::injectFaultForTesting).
enum class InjectedFault {
  kNaN,     // the first free particle's position becomes NaN before the constraints are solved
  kBlowUp,  // after they are, the first free particle gets 1000 x solver.max_speed more speed
};

struct GraspResult {
  bool success = false;
  std::string message;
  int grasped_count = 0;
};

class Simulation {
 public:
  // Validates the scene (throws ConfigError) and builds the initial state.
  explicit Simulation(const SceneConfig& scene);

  // Back to the initial state (time 0, initial positions, nothing grasped, trajectories restart).
  void reset();

  // Advances by one step of 1/step_rate s.
  void step() { step(1.0 / scene_.step_rate); }
  void step(double dt);

  double time() const { return time_; }
  const SceneConfig& scene() const { return scene_; }
  const Particles& particles() const { return particles_; }
  // Direct access for tools and tests that set up a disturbance (a kick, an initial overlap).
  Particles& mutableParticles() {
    state_measured_ = false;
    return particles_;
  }
  const ClothTopology& topology() const { return topology_; }
  // The particles as built, the state reset() returns to.
  const Particles& initialParticles() const { return initial_particles_; }
  // The last step's figures (the solver's, solver().stats()), with max_strain, mean_strain and
  // max_penetration of the state as it is now. Those three are measured here, when asked, once
  // per state, not in the step: a node stepping at 333 Hz and reporting at 30 Hz would measure
  // eleven states for each one it reports (a pass over every link and every particle's
  // obstacles).
  const StepStats& stats() const;
  const Solver& solver() const { return solver_; }

  // Indices of the particles that are pinned or grasped right now, written into `out`.
  void kinematicIndices(std::vector<unsigned>& out) const;

  // Grippers. Index -1 means "no such gripper".
  int gripperIndex(const std::string& name) const;
  int gripperCount() const { return static_cast<int>(grippers_.size()); }
  const std::string& gripperName(int gripper) const;
  // solver.taut_chains: the particles held straight in the last step, and the ends holding them.
  const TautChains& tautChains() const { return taut_chains_; }
  // The pose the gripper reaches at the end of the next step. A live pose stops its trajectory.
  // A pose with a poseProblem() is refused (false) and the gripper keeps its course.
  bool setGripperPose(int gripper, const Pose& pose);
  const Pose& gripperPose(int gripper) const;
  bool gripperGrasping(int gripper) const;
  GraspResult setGrasp(int gripper, bool grasp);
  // Force (N) the held particles exerted on the gripper over the last step (impulse / dt): every
  // constraint and contact acting on them (stretch, bending, tethers, particle and self-contacts;
  // every method), plus their own weight, minus their mass times their acceleration. A cloth
  // hanging at rest from this gripper alone gives its whole weight, pointing down.
  Eigen::Vector3d gripperForce(int gripper) const;

  // Obstacles. Index -1 means "no such obstacle".
  int obstacleIndex(const std::string& name) const;
  int obstacleCount() const { return static_cast<int>(scene_.obstacles.size()); }
  // The obstacle as it stands now (pose at the end of the last step).
  const ObstacleConfig& obstacle(int obstacle) const { return collisions_.obstacles()[obstacle]; }
  // The pose the obstacle reaches at the end of the next step (moved as a kinematic body). A
  // pose with a poseProblem() is refused (false).
  bool setObstaclePose(int obstacle, const Pose& pose);
  // The contact handling: candidate counts of the last step (collisions().stats()).
  const Collisions& collisions() const { return collisions_; }

  // Robot links (scene.robot.model.links; index -1 means "no such link"). Only links with collision
  // elements collide. Without live poses the links follow robot.joint_trajectory by forward
  // kinematics (robot.pose places the root); a live pose takes that link off the trajectory.
  int robotLinkCount() const;
  int robotLinkIndex(const std::string& name) const;
  const std::string& robotLinkName(int link) const;
  bool robotLinkHasCollision(int link) const;
  // The pose the link reaches at the end of the next step (moved as a kinematic body, swept
  // continuously). A pose with a poseProblem() is refused (false).
  bool setRobotLinkPose(int link, const Pose& pose);
  // The link's pose now (end of the last step).
  const Pose& robotLinkPose(int link) const;
  // A disabled link does not collide (the node disables a link whose tf is missing). When it is
  // enabled again it is placed at the next pose given, without sweeping the way in between.
  void setRobotLinkEnabled(int link, bool enabled);
  bool robotLinkEnabled(int link) const;

  // Live tuning: applied at the next step. Throws ConfigError on an invalid value.
  void setSolverConfig(const SolverConfig& solver);
  void setClothCompliance(double stretch_compliance, double bend_compliance);
  void setFriction(const FrictionConfig& friction);

  // Saving and restoring (saved_state.h). getState captures everything the next step needs;
  // setState continues from a state got from a Simulation of the same scene, and the steps after
  // it are bit for bit those that followed the saved state. A state that does not fit this scene
  // (counts, names, indices, non-finite values) is refused: false, `reason` names the field and
  // index, and nothing changes. Scene settings (live tuning included) stay as they are.
  void getState(SimulationState& state) const;
  bool setState(const SimulationState& state, std::string& reason);

  // Accuracy metrics of the current state (strain, penetration, self-intersections, energy).
  Metrics computeMetrics() const;

  // What is wrong with the initial state without making it invalid (an overlapping start):
  // particles starting inside an obstacle (pushed out over the first steps, no faster than the
  // contact's separation speed) and a cloth starting self-intersecting (self-collision keeps
  // layers apart but cannot untangle them); granular particles overlapping each other are simply
  // separated (CollisionGranular.OverlappingParticlesSeparateWithoutPopping). One message each,
  // naming the obstacle and the first particle; the node logs them at start-up.
  const std::vector<std::string>& startWarnings() const { return start_warnings_; }

  // Fault recovery (off by default; the node turns it on). After each step every particle is
  // checked: a non-finite position or velocity, or a free particle faster than solver.max_speed,
  // means the step failed (a bad input that got past the checks, an unstable setting, a bug).
  // The step is then undone: every free particle goes back to its position at the start of the
  // step, at rest (the momentum that blew up is not replayed), kinematic particles stay where
  // their grippers put them, and time goes on. Off, a failed step stays as it is: the benchmarks
  // and stability tests must see a method diverge.
  void setFaultRecovery(bool on) { fault_recovery_ = on; }
  // Between steps (never inside one): buffers an extreme step grew beyond what build() reserved
  // go back to that reserve, contents kept, so a long-running node does not keep the peak of
  // every extreme for good. The results do not change. Returns the bytes released.
  std::size_t releaseExcessCapacity() { return collisions_.releaseExcessCapacity(); }
  bool faultRecovery() const { return fault_recovery_; }
  // Steps undone since construction (reset does not clear it), whether the last one was, and the
  // fault of the latest undone step.
  std::uint64_t restoredSteps() const { return restored_steps_; }
  bool lastStepRestored() const { return last_step_restored_; }
  // Sleeping (solver.sleep_speed): whether the scene sleeps now, and the steps it slept through
  // since it was built (each cost a check, not a solve).
  bool asleep() const { return asleep_; }
  long sleptSteps() const { return slept_steps_; }
  // Wakes a sleeping scene: anything from outside that could move it calls this (grasp, state,
  // reset, solver or cloth parameters); the step's own checks catch moving pins, grippers and
  // colliders.
  void wake();
  const StepFault& lastFault() const { return last_fault_; }
  // The check itself, on the current state (kNone: the state can stand).
  StepFault findFault() const;
  // Test hook: corrupts the next step from inside (InjectedFault says where), so a test can see
  // the recovery catch it.
  void injectFaultForTesting(InjectedFault fault) { injected_fault_ = fault, inject_ = true; }

 private:
  // stats(): the measures of the current state, whether they are still current (a step, a
  // reset, a restored state or direct access to the particles makes them stale), and the
  // solver's figures with them, as returned.
  struct StateMeasures {
    double max_strain = 0.0;
    double mean_strain = 0.0;
    double max_penetration = 0.0;
  };
  mutable StateMeasures measures_;
  mutable bool state_measured_ = false;
  mutable StepStats reported_stats_;
  struct GripperState {
    Pose pose;          // pose at the end of the last step
    Pose target;        // pose at the end of the next step
    bool live = false;  // a pose message arrived: the trajectory is no longer followed
    bool grasping = false;
    std::vector<int> grasped;                    // particle indices
    std::vector<Eigen::Vector3d> local_offsets;  // grasped particle positions in the gripper frame
    // Linear velocity over the last step (reported in the state; released particles keep their
    // own velocity, which includes the gripper's rotation: releaseGrasp).
    Eigen::Vector3d velocity = Eigen::Vector3d::Zero();
    std::size_t next_waypoint = 0;  // first waypoint whose grasp event is pending
  };

  // A robot link: its colliders [first_collider, first_collider + collider_count) in collisions_.
  struct RobotLinkState {
    int first_collider = 0;
    int collider_count = 0;
    Pose pose;          // at the end of the last step
    Pose target;        // at the end of the next step
    bool live = false;  // a pose was given: robot.joint_trajectory no longer poses it
    bool enabled = true;
  };

  void build();
  void buildRobot();
  void followJointTrajectory(double t);
  void moveRobotColliders();
  void followTrajectories(double t_end);
  void updateKinematicTargets(double dt);
  int changeGrasp(int gripper, bool grasp);
  void releaseGrasp(GripperState& gripper);
  void kinematicSetChanged();
  void undoStep(const StepFault& fault);
  void findStartWarnings();
  bool canSleepThrough() const;
  void stepAwake(double dt, bool targets_set);
  void stepHeld(double dt);
  void updateSleep(double dt);
  void injectFault(double dt);
  // setState's check: empty when the state fits this scene, else what does not.
  std::string checkState(const SimulationState& state) const;

  SceneConfig scene_;
  Particles particles_;
  Particles initial_particles_;
  ClothTopology topology_;
  // Rebuilds topology_.tethers on a grasp or release (cloth.tethers), inside the step when the
  // grasp is scripted: its scratch is sized in build().
  TetherBuilder tether_builder_;
  // solver.taut_chains: rows and columns held straight while exactly taut, step by step.
  TautChains taut_chains_;
  bool chainsInextensible() const;
  // Per cloth particle, the body holding it while it is kinematic: -1 pinned, g gripper g (so
  // that two grippers' neighbouring patches are two groups of anchors for the tethers).
  std::vector<int> anchor_holder_;
  Solver solver_;
  Collisions collisions_;
  std::vector<GripperState> grippers_;
  std::vector<RobotLinkState> links_;  // one per scene_.robot.model.links
  // robot.joint_trajectory with every joint's position at every waypoint (a joint a waypoint does
  // not name keeps its previous value; 0 before the first), and scratch space for the step.
  std::vector<std::vector<double>> joint_waypoints_;
  std::vector<double> joint_positions_;
  std::vector<Pose> link_poses_;
  double time_ = 0.0;
  // Fault recovery: the free particles' positions at the start of the step (sized in build(),
  // so the copy each step allocates nothing).
  std::vector<std::string> start_warnings_;
  bool fault_recovery_ = false;
  Vec3Array good_position_;
  std::uint64_t restored_steps_ = 0;
  bool last_step_restored_ = false;
  // Sleeping: how long every free particle has stayed within sleep_speed x sleep_time of where it
  // was when the stillness began (still_from_, sized in build()), whether the scene sleeps, the
  // particles' bounds when it fell asleep, and the collider change count then.
  double still_time_ = 0.0;
  bool still_begun_ = false;
  Vec3Array still_from_;
  bool asleep_ = false;
  long slept_steps_ = 0;
  Vec3 sleep_lo_ = Vec3::Zero();
  Vec3 sleep_hi_ = Vec3::Zero();
  double sleep_margin_ = 0.0;  // m around those bounds where a moving collider wakes the scene
  long sleep_collider_changes_ = 0;
  StepFault last_fault_;
  bool inject_ = false;
  InjectedFault injected_fault_ = InjectedFault::kNaN;
};

// Live poses (grippers, obstacles, robot links) farther than this from the scene origin in any
// coordinate are refused: nothing a robot handles is 10 km away, and an absurd coordinate (1e300
// from a corrupted message) would overflow the step's squares into Inf and NaN.
constexpr double kMaxPoseCoordinate = 1e4;  // m

// Whether a live pose may enter the simulation: a finite position within kMaxPoseCoordinate, a
// finite orientation of non-zero length. Empty when it may, else why not.
std::string poseProblem(const Pose& pose);

}  // namespace pbd_cloth
