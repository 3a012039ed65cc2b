// A whole scene in motion: the particles and constraints built from a SceneConfig, the solver, the
// grippers (scripted trajectory or live poses, grasp and release) and the obstacles. ROS-free: the
// node and cloth_bench both drive this class, so a scene replays offline exactly as in the node.
#pragma once

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "pbd_cloth/config/scene_config.h"
#include "pbd_cloth/constraints/tethers.h"
#include "pbd_cloth/model/particles.h"
#include "pbd_cloth/sim/accuracy_controller.h"
#include "pbd_cloth/sim/colliders.h"
#include "pbd_cloth/sim/fault_guard.h"
#include "pbd_cloth/sim/grippers.h"
#include "pbd_cloth/sim/live_pose.h"
#include "pbd_cloth/sim/metrics.h"
#include "pbd_cloth/sim/robot_links.h"
#include "pbd_cloth/sim/sleeping.h"
#include "pbd_cloth/solver/solver.h"
#include "pbd_cloth/state/saved_state.h"

namespace pbd_cloth {

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
  // The scene's ropes (Cosserat rods; their particles are among particles(), from each one's
  // first_particle on): orientations and angular velocities of their segments.
  const std::vector<Rod>& ropes() const { return ropes_; }
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

  // Grippers. Index -1 means "no such gripper". Their poses and holds: grippers() (count(),
  // pose(g), grasping(g)); they move and grasp through the calls below, which keep the rest of
  // the scene (tethers, sleep) in step with them.
  const Grippers& grippers() const { return grippers_; }
  int gripperIndex(const std::string& name) const;
  const std::string& gripperName(int gripper) const;
  // The pose the gripper reaches at the end of the next step. A live pose stops its trajectory.
  // A pose with a poseProblem() is refused (false) and the gripper keeps its course.
  bool setGripperPose(int gripper, const Pose& pose) { return grippers_.setPose(gripper, pose); }
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
  const Collider& obstacle(int obstacle) const { return collisions_.obstacles()[obstacle]; }
  // The pose the obstacle reaches at the end of the next step (moved as a kinematic body). A
  // pose with a poseProblem() is refused (false).
  bool setObstaclePose(int obstacle, const Pose& pose);
  // The contact handling: candidate counts of the last step (collisions().stats()).
  const Collisions& collisions() const { return collisions_; }

  // Robot links (scene.robot.model.links; index -1 means "no such link"). Only links with collision
  // elements collide. Without live poses the links follow robot.joint_trajectory by forward
  // kinematics (robot.pose places the root); a live pose takes that link off the trajectory.
  // Their poses now (end of the last step) and whether they collide: robotLinks() (count(),
  // pose(l), hasCollision(l), enabled(l)).
  const RobotLinks& robotLinks() const { return links_; }
  int robotLinkIndex(const std::string& name) const;
  const std::string& robotLinkName(int link) const;
  // The pose the link reaches at the end of the next step (moved as a kinematic body, swept
  // continuously). A pose with a poseProblem() is refused (false).
  bool setRobotLinkPose(int link, const Pose& pose) { return links_.setPose(link, pose); }
  // A disabled link does not collide (the node disables a link whose tf is missing). When it is
  // enabled again it is placed at the next pose given, without sweeping the way in between.
  void setRobotLinkEnabled(int link, bool enabled) {
    links_.setEnabled(link, enabled, collisions_);
  }

  // Accuracy on demand (solver.target_max_strain, solver.target_penetration): what the last
  // step reached against the targets. Without a target, only `active` (false) and `substeps`.
  struct AccuracyReport {
    bool active = false;
    double target_max_strain = 0.0;      // solver.target_max_strain (0: none)
    double target_penetration = 0.0;     // solver.target_penetration (m, 0: none)
    double structural_max_strain = 0.0;  // reached by the last step (its final attempt)
    double max_penetration = 0.0;        // m; measured only with a penetration target
    bool target_met = true;              // the last step met every target
    bool budget_exhausted = false;       // ... did not, at solver.max_substeps
    int substeps = 0;                    // of the last step's final attempt
    int substeps_run = 0;                // over all its attempts (its cost)
    int redos = 0;                       // times the last step was run again
  };
  const AccuracyReport& accuracy() const { return accuracy_report_; }
  const AccuracyController& accuracyController() const { return accuracy_; }

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
  // and stability tests must see a method diverge. What it undid: faultGuard() (restoredSteps(),
  // reset does not clear it; lastStepRestored(); lastFault(), of the latest undone step).
  void setFaultRecovery(bool on) { fault_guard_.setEnabled(on); }
  const FaultGuard& faultGuard() const { return fault_guard_; }
  // The check itself, on the current state (kNone: the state can stand).
  StepFault findFault() const;
  // Test hook: corrupts the next step from inside (InjectedFault says where), so a test can see
  // the recovery catch it.
  void injectFaultForTesting(InjectedFault fault) { fault_guard_.inject(fault); }

  // Sleeping (solver.sleep_speed, sleeping.h): whether the scene sleeps now, and the steps it
  // slept through since it was built: sleeping() (asleep(), sleptSteps()).
  const Sleeping& sleeping() const { return sleeping_; }
  // Wakes a sleeping scene: anything from outside that could move it calls this (grasp, state,
  // reset, solver or cloth parameters); the step's own checks catch moving pins, grippers and
  // colliders.
  void wake() { sleeping_.wake(); }

  // Between steps (never inside one): buffers an extreme step grew beyond what build() reserved
  // go back to that reserve, contents kept, so a long-running node does not keep the peak of
  // every extreme for good. The results do not change. Returns the bytes released.
  std::size_t releaseExcessCapacity() { return collisions_.releaseExcessCapacity(); }

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
  void build();
  // The solve of a step: once, or with a target until it is met or the budget is spent.
  void solveStep(double dt);
  void moveKinematicBodies(double dt);
  void followTrajectories(double t_end);
  void updateKinematicTargets(double dt);
  int changeGrasp(int gripper, bool grasp);
  void kinematicSetChanged();
  void findStartWarnings();
  void stepAwake(double dt, bool targets_set);
  // setState's check: empty when the state fits this scene, else what does not.
  std::string checkState(const SimulationState& state) const;

  SceneConfig scene_;
  Particles particles_;
  Particles initial_particles_;
  ClothTopology topology_;
  // Rebuilds topology_.tethers on a grasp or release (cloth.tethers), inside the step when the
  // grasp is scripted: its scratch is sized in build().
  TetherBuilder tether_builder_;
  // Per cloth particle, the body holding it while it is kinematic: -1 pinned, g gripper g (so
  // that two grippers' neighbouring patches are two groups of anchors for the tethers).
  std::vector<int> anchor_holder_;
  Solver solver_;
  Collisions collisions_;
  Grippers grippers_;
  RobotLinks links_;  // one per scene_.robot.model.links
  double time_ = 0.0;
  std::vector<std::string> start_warnings_;
  FaultGuard fault_guard_;
  AccuracyController accuracy_;
  AccuracyReport accuracy_report_;
  Particles redo_start_;    // the particles at the start of a step a target may run again
  std::vector<Rod> ropes_;  // scene.ropes as rods (the solver steps them)
  std::vector<Rod> ropes_redo_start_;  // at the start of a step a target may run again
  std::vector<Rod> ropes_step_start_;  // at the start of the step, for the fault guard's undo
  Sleeping sleeping_;
};

}  // namespace pbd_cloth
