#include "pbd_cloth/sim/simulation.h"

#include <algorithm>
#include <cmath>
#include <sstream>

#include "pbd_cloth/sim/cloth_builder.h"

namespace pbd_cloth {

Simulation::Simulation(const SceneConfig& scene) : scene_(scene) {
  validate(scene_);
  const RobotConfig& robot = scene_.robot;
  if (robot.enabled && robot.model.links.empty()) {
    throw ConfigError("robot",
                      "no URDF loaded: give robot.urdf_file, or (node) the URDF in the parameter "
                      "named by robot.description");
  }
  links_.readTrajectory(robot);
  build();
  findStartWarnings();
}

void Simulation::findStartWarnings() {
  // 1 mm: a cloth laid on a surface within its thickness is resting, not overlapping.
  constexpr double kSlack = 1e-3;
  std::vector<int> inside, first;
  collisions_.countInside(particles_, kSlack, inside, first);
  for (std::size_t k = 0; k < inside.size(); ++k) {
    if (inside[k] == 0) continue;
    std::ostringstream out;
    out << "overlapping start: " << inside[k] << " particle(s) start more than 1 mm inside "
        << "obstacle '" << collisions_.obstacles()[k].name << "' (first: particle " << first[k]
        << "); they are pushed out over the first steps";
    start_warnings_.push_back(out.str());
  }
  if (!topology_.triangles.empty()) {
    const int crossings = countSelfIntersections(particles_, topology_);
    if (crossings > 0) {
      start_warnings_.push_back(
          "overlapping start: the cloth starts self-intersecting (" + std::to_string(crossings) +
          " edge-triangle crossings); self-collision keeps its layers apart but cannot untangle "
          "them");
    }
  }
}

void Simulation::build() {
  buildScene(scene_, particles_, topology_);
  initial_particles_ = particles_;
  collisions_.configure(collisionSettings(scene_));
  links_.build(scene_.robot, collisions_);
  solver_.configure(scene_.solver, clothMaterial(scene_.cloth));
  accuracy_ = AccuracyController();
  accuracy_.configure(scene_.solver);
  accuracy_report_ = AccuracyReport();
  redo_start_ = particles_;  // sized once: a step copies into it without allocating
  solver_.prepare(particles_, topology_);
  ropes_ = buildRopes(scene_, particles_.cloth_count);
  ropes_redo_start_ = ropes_;  // sized once: steps copy into them without allocating
  ropes_step_start_ = ropes_;
  solver_.setRopes(&ropes_);
  collisions_.prepare(particles_, topology_);
  collisions_.rememberStepStart();  // sizes its buffer
  solver_.mutableStats() = StepStats();
  solver_.initializeVelocities(particles_, 1.0 / scene_.step_rate);
  anchor_holder_.assign(particles_.cloth_count, -1);
  if (scene_.cloth.tethers) {
    // Room for the tethers of the pins' groups and one more group per gripper (a gripper whose
    // hold spans separate layers of a folded cloth makes a group of each: more allocates once).
    const int groups = tether_builder_.countGroups(particles_, topology_, anchor_holder_) +
                       static_cast<int>(scene_.grippers.size());
    tether_builder_.reserve(particles_, topology_, groups, topology_.tethers);
  }
  grippers_.build(scene_.grippers, particles_.cloth_count);
  time_ = 0.0;
  fault_guard_.build(particles_);
  sleeping_.build(particles_);
  state_measured_ = false;
}

int Simulation::robotLinkIndex(const std::string& name) const {
  return scene_.robot.model.linkIndex(name);
}

const std::string& Simulation::robotLinkName(int link) const {
  return scene_.robot.model.links[link].name;
}

// Starts again from the scene as configured now: live-tuned settings (setSolverConfig, ...) are
// kept, since they were written into scene_.
void Simulation::reset() {
  build();
  wake();
}

void Simulation::kinematicIndices(std::vector<unsigned>& out) const {
  out.clear();
  for (int i = 0; i < particles_.size(); ++i) {
    if (particles_.isKinematic(i)) out.push_back(static_cast<unsigned>(i));
  }
}

int Simulation::gripperIndex(const std::string& name) const {
  for (std::size_t g = 0; g < scene_.grippers.size(); ++g) {
    if (scene_.grippers[g].name == name) return static_cast<int>(g);
  }
  return -1;
}

const std::string& Simulation::gripperName(int gripper) const {
  return scene_.grippers[gripper].name;
}

GraspResult Simulation::setGrasp(int gripper, bool grasp) {
  const GripperConfig& config = scene_.grippers[gripper];
  GraspResult result;
  result.grasped_count = changeGrasp(gripper, grasp);
  if (!grasp) {
    result.success = true;
    result.message = "released " + std::to_string(result.grasped_count) + " particles";
    return result;
  }
  const Pose& pose = grippers_.pose(gripper);
  result.success = result.grasped_count > 0;
  std::ostringstream message;
  if (result.success) {
    message << "grasped " << result.grasped_count << " particles";
  } else {
    message << "no free cloth particle within radius " << config.radius << " m of gripper '"
            << config.name << "' at (" << pose.position.transpose() << ")";
  }
  result.message = message.str();
  return result;
}

// A grasp or a release, scripted (inside the step) or from outside, then what follows from it.
// Allocates nothing (Grippers::changeGrasp) but for a tethers' rebuild beyond the groups of
// anchors build() expected.
int Simulation::changeGrasp(int gripper, bool grasp) {
  const int count = grippers_.changeGrasp(gripper, grasp, scene_.grippers[gripper], particles_,
                                          initial_particles_);
  kinematicSetChanged();
  return count;
}

void Simulation::kinematicSetChanged() {
  wake();                   // a grasp or a release: the cloth is held differently
  state_measured_ = false;  // the penetration measure leaves kinematic particles out
  if (scene_.cloth.tethers) {
    std::fill(anchor_holder_.begin(), anchor_holder_.end(), -1);
    for (int g = 0; g < grippers_.count(); ++g) {
      for (int i : grippers_[g].grasped) anchor_holder_[i] = g;
    }
    tether_builder_.build(particles_, topology_, scene_.cloth.spacing, topology_.tethers,
                          anchor_holder_);
  }
}

Eigen::Vector3d Simulation::gripperForce(int gripper) const {
  return grippers_.force(gripper, solver_.supportForce());
}

int Simulation::obstacleIndex(const std::string& name) const {
  const auto& obstacles = scene_.obstacles;
  for (std::size_t k = 0; k < obstacles.size(); ++k) {
    if (obstacles[k].name == name) return static_cast<int>(k);
  }
  return -1;
}

bool Simulation::setObstaclePose(int obstacle, const Pose& pose) {
  if (!poseProblem(pose).empty()) return false;
  Pose target = pose;
  target.orientation.normalize();
  return collisions_.setObstacleTarget(obstacle, target);
}

void Simulation::setSolverConfig(const SolverConfig& solver) {
  SceneConfig candidate = scene_;
  candidate.solver = solver;
  validate(candidate);
  scene_.solver = solver;
  solver_.configure(scene_.solver, clothMaterial(scene_.cloth));
  accuracy_.configure(scene_.solver);
  wake();  // gravity, damping or the solve changed: the rest state may no longer be one
}

void Simulation::setClothCompliance(double stretch_compliance, double bend_compliance) {
  SceneConfig candidate = scene_;
  candidate.cloth.stretch_compliance = stretch_compliance;
  candidate.cloth.bend_compliance = bend_compliance;
  validate(candidate);
  scene_.cloth = candidate.cloth;
  wake();
  // A scene built with bending off (bend_compliance < 0) has no hinges: turning it on builds them
  // now, at the rest shape the scene was built with, exactly those a build with this compliance
  // would have, so bending acts from the next step and a reset() keeps it. (Turned off, the hinges
  // stay and are skipped.) prepare() sizes the solver's multipliers for them; it also clears the
  // constraint forces of the last step, so gripperForce() reads zero until the next step.
  if (bend_compliance >= 0.0 && topology_.bend.empty() && !topology_.triangles.empty()) {
    buildBending(initial_particles_.position, topology_);
    solver_.prepare(particles_, topology_);
  }
  solver_.configure(solver_.config(), clothMaterial(scene_.cloth));
}

void Simulation::setFriction(const FrictionConfig& friction) {
  SceneConfig candidate = scene_;
  candidate.cloth.friction = friction;
  validate(candidate);
  scene_.cloth.friction = friction;
  collisions_.setFriction(toFriction(friction));
  wake();  // less friction may let a cloth at rest slide
}

// Scripted grippers: grasp events due by the start of this step fire, and the target is the
// trajectory's pose at the end of the step. A live pose (setGripperPose) replaces the script.
// A repeating trajectory (grippers[i].repeat) runs again every period (its last waypoint's t):
// next_waypoint then counts the waypoints passed over every period, period k's waypoint i being
// at k period + t_i.
void Simulation::followTrajectories(double t_end) {
  for (int g = 0; g < grippers_.count(); ++g) {
    GripperState& state = grippers_[g];
    const GripperConfig& config = scene_.grippers[g];
    const auto& trajectory = config.trajectory;
    if (state.live || trajectory.empty()) continue;
    const std::size_t count = trajectory.size();
    const double period = config.repeat ? trajectory.back().t : 0.0;
    while (config.repeat || state.next_waypoint < count) {
      const std::size_t index = state.next_waypoint % count;
      const double repeats = static_cast<double>(state.next_waypoint / count);
      if (repeats * period + trajectory[index].t > time_ + 1e-9) break;
      const int grasp = trajectory[index].grasp;
      if (grasp >= 0) changeGrasp(g, grasp == 1);
      ++state.next_waypoint;
    }
    state.target = trajectoryPose(
        trajectory, config.repeat ? t_end - std::floor(t_end / period) * period : t_end);
  }
}

// Kinematic particles move from where they are to where their gripper (or pin) puts them at the
// end of the step; the solver interpolates across substeps.
void Simulation::updateKinematicTargets(double dt) {
  for (int i = 0; i < particles_.size(); ++i) {
    particles_.kinematic_from[i] = particles_.position[i];
    particles_.kinematic_to[i] = particles_.position[i];
  }
  grippers_.moveHeld(particles_, dt);
}

void Simulation::step(double dt) {
  if (sleeping_.asleep()) {
    moveKinematicBodies(dt);
    // An injected fault is for a step that solves.
    if (!fault_guard_.injecting() && sleeping_.canSleepThrough(particles_, collisions_)) {
      grippers_.endStep();
      links_.endStep();
      collisions_.endStep();  // colliders at their (unchanged) targets
      time_ += dt;
      sleeping_.countSleptStep();
      accuracy_report_.substeps_run = accuracy_report_.redos = 0;  // no solve: the state stands
      StepStats& stats = solver_.mutableStats();
      stats.sim_time += dt;
      stats.step_wall_time = stats.predict_time = stats.collide_time = 0.0;
      stats.project_time = stats.update_time = stats.contact_time = 0.0;
      stats.iterations = 0;
      stats.threads_used = 0;  // no solve
      stats.on_one_thread = false;
      fault_guard_.clearLastStepRestored();
      return;
    }
    wake();
    stepAwake(dt, /*targets_set=*/true);
    return;
  }
  stepAwake(dt, /*targets_set=*/false);
}

void Simulation::stepAwake(double dt, bool targets_set) {
  fault_guard_.rememberStart(particles_);
  // What the fault guard's undo restores the ropes' segments to (same sizes: no allocation).
  if (fault_guard_.enabled()) ropes_step_start_ = ropes_;
  if (!targets_set) moveKinematicBodies(dt);
  const double max_speed = scene_.solver.max_speed;
  fault_guard_.injectBeforeSolve(particles_, max_speed, dt);
  solveStep(dt);
  fault_guard_.injectAfterSolve(particles_, max_speed, dt);
  grippers_.endStep();
  links_.endStep();
  time_ += dt;
  fault_guard_.clearLastStepRestored();
  const bool undone = fault_guard_.checkStep(particles_, max_speed, time_);
  if (undone) {
    // The ropes' segments go back with their particles, at rest as the particles are.
    ropes_ = ropes_step_start_;
    for (Rod& rope : ropes_) {
      for (Vec3& omega : rope.angular_velocity) omega.setZero();
    }
  }
  state_measured_ = false;
  if (!undone) sleeping_.update(scene_.solver, particles_, collisions_, dt);
}

// With a target (accuracy_controller.h), the step runs with the controller's substeps; far over
// the target it runs again from its start with more (the particles and the collisions' step
// state restored, the time not advanced twice), at most AccuracyController::kMaxRedos times.
// Without one, the solver steps exactly as configured.
void Simulation::solveStep(double dt) {
  AccuracyReport& report = accuracy_report_;
  report.active = accuracy_.active();
  if (!report.active) {
    solver_.step(dt, particles_, topology_, collisions_);
    report.substeps = report.substeps_run = solver_.stats().substeps;
    return;
  }
  report.target_max_strain = accuracy_.targetStrain();
  report.target_penetration = accuracy_.targetPenetration();
  redo_start_ = particles_;  // same sizes: no allocation
  ropes_redo_start_ = ropes_;
  collisions_.rememberStepStart();
  report.substeps_run = 0;
  for (int attempt = 0;; ++attempt) {
    solver_.setSubsteps(accuracy_.substeps());
    solver_.step(dt, particles_, topology_, collisions_);
    report.substeps = accuracy_.substeps();
    report.substeps_run += report.substeps;
    double mean_strain = 0.0;
    computeStructuralStrain(particles_, topology_, report.structural_max_strain, mean_strain);
    report.max_penetration =
        accuracy_.measuresPenetration() ? collisions_.maxPenetration(particles_, topology_) : 0.0;
    const double ratio = accuracy_.ratio(report.structural_max_strain, report.max_penetration);
    if (accuracy_.redo(ratio, attempt)) {
      particles_ = redo_start_;
      ropes_ = ropes_redo_start_;
      collisions_.restoreStepStart();
      solver_.mutableStats().sim_time -= dt;
      continue;
    }
    report.redos = attempt;
    report.target_met = AccuracyController::met(ratio);
    report.budget_exhausted =
        !report.target_met && accuracy_.substeps() >= scene_.solver.max_substeps;
    accuracy_.update(ratio);
    break;
  }
}

// Where every kinematic body is going in the step: grippers (and their grasp events), robot links
// and their colliders, and the held and pinned particles with them.
void Simulation::moveKinematicBodies(double dt) {
  followTrajectories(time_ + dt);
  links_.followJointTrajectory(scene_.robot, time_ + dt);
  links_.moveColliders(scene_.robot.model, collisions_);
  updateKinematicTargets(dt);
}

const StepStats& Simulation::stats() const {
  if (!state_measured_) {
    computeStrain(particles_, topology_, measures_.max_strain, measures_.mean_strain);
    measures_.max_penetration = collisions_.maxPenetration(particles_, topology_);
    state_measured_ = true;
  }
  reported_stats_ = solver_.stats();
  reported_stats_.max_strain = measures_.max_strain;
  reported_stats_.mean_strain = measures_.mean_strain;
  reported_stats_.max_penetration = measures_.max_penetration;
  return reported_stats_;
}

StepFault Simulation::findFault() const {
  return pbd_cloth::findFault(particles_, scene_.solver.max_speed, time_);
}

Metrics Simulation::computeMetrics() const {
  return measureMetrics(particles_, topology_, collisions_, scene_.solver);
}

}  // namespace pbd_cloth
