#include "pbd_cloth/sim/simulation.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>

#include "pbd_cloth/sim/cloth_builder.h"

namespace pbd_cloth {

namespace {

// Pose of a scripted trajectory at time t: linear/slerp between waypoints, held after the last.
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

}  // namespace

Simulation::Simulation(const SceneConfig& scene) : scene_(scene) {
  validate(scene_);
  const RobotConfig& robot = scene_.robot;
  if (robot.enabled && robot.model.links.empty()) {
    throw ConfigError("robot",
                      "no URDF loaded: give robot.urdf_file, or (node) the URDF in the parameter "
                      "named by robot.description");
  }
  // Every waypoint as a full vector of joint positions, so the step only interpolates.
  const std::size_t joint_count = robot.model.joints.size();
  std::vector<double> previous(joint_count, 0.0);
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
  collisions_.configure(scene_);
  buildRobot();
  solver_.configure(scene_.solver, scene_.cloth);
  solver_.prepare(particles_, topology_);
  collisions_.prepare(particles_, topology_);
  taut_chains_.build(particles_, topology_);
  solver_.mutableStats() = StepStats();
  solver_.initializeVelocities(particles_, 1.0 / scene_.step_rate);
  grippers_.assign(scene_.grippers.size(), GripperState());
  anchor_holder_.assign(particles_.cloth_count, -1);
  if (scene_.cloth.tethers) {
    // Room for the tethers of the pins' groups and one more group per gripper (a gripper whose
    // hold spans separate layers of a folded cloth makes a group of each: more allocates once).
    const int groups = tether_builder_.countGroups(particles_, topology_, anchor_holder_) +
                       static_cast<int>(scene_.grippers.size());
    tether_builder_.reserve(particles_, topology_, groups, topology_.tethers);
  }
  for (std::size_t g = 0; g < grippers_.size(); ++g) {
    // Room for every cloth particle (28 bytes each), so a grasp inside the step never allocates.
    grippers_[g].grasped.reserve(particles_.cloth_count);
    grippers_[g].local_offsets.reserve(particles_.cloth_count);
    const auto& trajectory = scene_.grippers[g].trajectory;
    if (!trajectory.empty()) grippers_[g].pose = grippers_[g].target = trajectory.front().pose;
  }
  time_ = 0.0;
  good_position_ = particles_.position;
  still_from_ = particles_.position;
  still_begun_ = false;
  still_time_ = 0.0;
  last_step_restored_ = false;
  state_measured_ = false;
}

// The robot's collision elements become colliders after the obstacles, posed by forward kinematics
// at the start of robot.joint_trajectory (all joints at 0 without one).
void Simulation::buildRobot() {
  const RobotModel& model = scene_.robot.model;
  links_.assign(model.links.size(), RobotLinkState());
  if (model.links.empty()) return;
  followJointTrajectory(0.0);
  for (std::size_t l = 0; l < model.links.size(); ++l) {
    RobotLinkState& link = links_[l];
    link.pose = link.target;
    link.first_collider = static_cast<int>(collisions_.obstacles().size());
    for (const ObstacleConfig& element : model.links[l].collisions) {
      ObstacleConfig collider = element;
      collider.pose = link.pose.compose(element.pose);
      collisions_.addCollider(collider);
      ++link.collider_count;
    }
  }
}

// Targets of the links that no live pose drives: forward kinematics of the joint trajectory at t.
void Simulation::followJointTrajectory(double t) {
  const RobotConfig& robot = scene_.robot;
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

// Every collision element follows its link: element pose = link pose composed with its origin.
void Simulation::moveRobotColliders() {
  const RobotModel& model = scene_.robot.model;
  for (std::size_t l = 0; l < links_.size(); ++l) {
    const RobotLinkState& link = links_[l];
    for (int e = 0; e < link.collider_count; ++e) {
      collisions_.setObstacleTarget(link.first_collider + e,
                                    link.target.compose(model.links[l].collisions[e].pose));
    }
  }
}

int Simulation::robotLinkCount() const { return static_cast<int>(links_.size()); }

int Simulation::robotLinkIndex(const std::string& name) const {
  return scene_.robot.model.linkIndex(name);
}

const std::string& Simulation::robotLinkName(int link) const {
  return scene_.robot.model.links[link].name;
}

bool Simulation::robotLinkHasCollision(int link) const { return links_[link].collider_count > 0; }

std::string poseProblem(const Pose& pose) {
  if (!pose.position.allFinite() || !pose.orientation.coeffs().allFinite()) {
    return "not finite";
  }
  if (pose.position.cwiseAbs().maxCoeff() > kMaxPoseCoordinate) {
    return "position more than " + std::to_string(static_cast<int>(kMaxPoseCoordinate)) +
           " m from the scene origin";
  }
  // The node refuses near-zero quaternions before they get here; this is the core's own guard.
  if (!(pose.orientation.norm() > 1e-12)) return "orientation of zero length";
  return std::string();
}

bool Simulation::setRobotLinkPose(int link, const Pose& pose) {
  if (!poseProblem(pose).empty()) return false;
  links_[link].live = true;
  links_[link].target = pose;
  links_[link].target.orientation.normalize();
  return true;
}

const Pose& Simulation::robotLinkPose(int link) const { return links_[link].pose; }

void Simulation::setRobotLinkEnabled(int link, bool enabled) {
  RobotLinkState& state = links_[link];
  if (enabled && !state.enabled) state.pose = state.target;  // no sweep from where it was lost
  state.enabled = enabled;
  for (int e = 0; e < state.collider_count; ++e) {
    collisions_.setObstacleEnabled(state.first_collider + e, enabled);
  }
}

bool Simulation::robotLinkEnabled(int link) const { return links_[link].enabled; }

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

bool Simulation::setGripperPose(int gripper, const Pose& pose) {
  if (!poseProblem(pose).empty()) return false;
  grippers_[gripper].live = true;
  grippers_[gripper].target = pose;
  grippers_[gripper].target.orientation.normalize();
  return true;
}

const Pose& Simulation::gripperPose(int gripper) const { return grippers_[gripper].pose; }

bool Simulation::gripperGrasping(int gripper) const { return grippers_[gripper].grasping; }

GraspResult Simulation::setGrasp(int gripper, bool grasp) {
  const GripperConfig& config = scene_.grippers[gripper];
  GraspResult result;
  result.grasped_count = changeGrasp(gripper, grasp);
  if (!grasp) {
    result.success = true;
    result.message = "released " + std::to_string(result.grasped_count) + " particles";
    return result;
  }
  const Pose& pose = grippers_[gripper].pose;
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

// Grasp: every free cloth particle within the radius becomes kinematic, held at its offset in
// the gripper frame; release: they are free again. Returns how many were grasped (released).
// Composes no message, so the scripted events inside the step allocate nothing: grasped and
// local_offsets have room for every cloth particle from build(), and the tethers' rebuild
// (cloth.tethers) for the groups of anchors build() expected.
int Simulation::changeGrasp(int gripper, bool grasp) {
  GripperState& state = grippers_[gripper];
  const int released = static_cast<int>(state.grasped.size());
  releaseGrasp(state);
  if (grasp) {
    const GripperConfig& config = scene_.grippers[gripper];
    const Pose& pose = state.pose;
    const Eigen::Quaterniond to_local = pose.orientation.conjugate();
    for (int i = 0; i < particles_.cloth_count; ++i) {
      if (initial_particles_.isKinematic(i) || particles_.isKinematic(i)) continue;  // pinned/held
      if ((particles_.position[i] - pose.position).norm() > config.radius) continue;
      state.grasped.push_back(i);
      state.local_offsets.push_back(to_local * (particles_.position[i] - pose.position));
      particles_.inverse_mass[i] = 0.0;
      particles_.kinematic_from[i] = particles_.kinematic_to[i] = particles_.position[i];
    }
    state.grasping = !state.grasped.empty();
  }
  kinematicSetChanged();
  return grasp ? static_cast<int>(state.grasped.size()) : released;
}

// A released particle keeps the velocity it had in the gripper: the solver gives a held particle
// the velocity of its own prescribed path over the last substep, (x_to - x_from) / dt with
// x = p + R o, i.e. v + (R_to R_from^-1 - I) r / dt = v + omega x r to first order in the step's
// rotation (a chord, as every velocity here). So a gripper that turns while it lets go throws the
// far particles faster than the near ones; the gripper's linear velocity alone would not. Until a
// step has moved it, a particle grasped and released at once keeps its free velocity.
void Simulation::releaseGrasp(GripperState& gripper) {
  for (int i : gripper.grasped) particles_.inverse_mass[i] = 1.0 / particles_.mass[i];
  gripper.grasped.clear();
  gripper.local_offsets.clear();
  gripper.grasping = false;
}

void Simulation::kinematicSetChanged() {
  wake();                   // a grasp or a release: the cloth is held differently
  state_measured_ = false;  // the penetration measure leaves kinematic particles out
  if (scene_.cloth.tethers) {
    std::fill(anchor_holder_.begin(), anchor_holder_.end(), -1);
    for (std::size_t g = 0; g < grippers_.size(); ++g) {
      for (int i : grippers_[g].grasped) anchor_holder_[i] = static_cast<int>(g);
    }
    tether_builder_.build(particles_, topology_, scene_.cloth.spacing, topology_.tethers,
                          anchor_holder_);
  }
}

Eigen::Vector3d Simulation::gripperForce(int gripper) const {
  Eigen::Vector3d force = Eigen::Vector3d::Zero();
  const std::vector<int>& grasped = grippers_[gripper].grasped;
  for (int i : grasped) force += solver_.supportForce()[i];
  // A chain held straight between its ends (solver.taut_chains) rests on them: each end carries
  // the share of a held particle's support force that a beam's supports carry of a point load
  // (1 - s at end a, s at end b, s its place along the chain).
  auto holds = [&](int i) { return std::find(grasped.begin(), grasped.end(), i) != grasped.end(); };
  for (const TautChains::Held& h : taut_chains_.held()) {
    if (holds(h.end_a)) force += (1.0 - h.along) * solver_.supportForce()[h.particle];
    if (holds(h.end_b)) force += h.along * solver_.supportForce()[h.particle];
  }
  return force;
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
  solver_.configure(scene_.solver, scene_.cloth);
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
  solver_.configure(solver_.config(), scene_.cloth);
}

void Simulation::setFriction(const FrictionConfig& friction) {
  SceneConfig candidate = scene_;
  candidate.cloth.friction = friction;
  validate(candidate);
  scene_.cloth.friction = friction;
  collisions_.setFriction(friction);
  wake();  // less friction may let a cloth at rest slide
}

// Scripted grippers: grasp events due by the start of this step fire, and the target is the
// trajectory's pose at the end of the step. A live pose (setGripperPose) replaces the script.
void Simulation::followTrajectories(double t_end) {
  for (std::size_t g = 0; g < grippers_.size(); ++g) {
    GripperState& state = grippers_[g];
    const auto& trajectory = scene_.grippers[g].trajectory;
    if (state.live || trajectory.empty()) continue;
    while (state.next_waypoint < trajectory.size() &&
           trajectory[state.next_waypoint].t <= time_ + 1e-9) {
      const int grasp = trajectory[state.next_waypoint].grasp;
      if (grasp >= 0) changeGrasp(static_cast<int>(g), grasp == 1);
      ++state.next_waypoint;
    }
    state.target = trajectoryPose(trajectory, t_end);
  }
}

// Kinematic particles move from where they are to where their gripper (or pin) puts them at the
// end of the step; the solver interpolates across substeps.
void Simulation::updateKinematicTargets(double dt) {
  for (int i = 0; i < particles_.size(); ++i) {
    particles_.kinematic_from[i] = particles_.position[i];
    particles_.kinematic_to[i] = particles_.position[i];
  }
  for (GripperState& state : grippers_) {
    state.velocity = (state.target.position - state.pose.position) / dt;
    for (std::size_t k = 0; k < state.grasped.size(); ++k) {
      particles_.kinematic_to[state.grasped[k]] =
          state.target.position + state.target.orientation * state.local_offsets[k];
    }
  }
  // Taut chains between the kinematic particles join them for this step (released in step()).
  // Off, none is held, and the last held list goes too: release() must not free a particle a
  // gripper has grasped since. With tethers (cloth.tethers) a taut chain's particles are already
  // held: each is tethered to both ends, and the two tethers' spheres meet only at its place on
  // the segment. Holding them as kinematic particles as well changed nothing there but the
  // order of the sweep's corrections, and that for the worse: config/hanging.yaml at rest ended
  // at 0.12 % strain (compression next to its side edges) against 0.0042 % (doc/performance.md,
  // "Taut chains held straight").
  if (scene_.solver.taut_chains && !scene_.cloth.tethers && chainsInextensible()) {
    taut_chains_.hold(particles_);
  } else {
    taut_chains_.forget();
  }
}

// Links that cannot stretch: only then is a taut chain's straight shape the only one it may take.
bool Simulation::chainsInextensible() const {
  const SolverConfig& s = scene_.solver;
  if (scene_.cloth.stretch_compliance != 0.0 || s.method == Method::kMassSpring) return false;
  return s.method != Method::kPbd || s.stretch_stiffness == 1.0;
}

// Sleeping. A scene whose free particles all stayed slower than solver.sleep_speed for
// solver.sleep_time is at rest: its next solve would move nothing but rounding. Slower on average:
// each stayed within sleep_speed x sleep_time of where it was when the stillness began, so a
// resting garment whose contacts nudge a particle by micrometres in one substep and back (a
// velocity of a centimetre a second for that substep) still counts as still. It then sleeps:
// a step checks what could move it, and while nothing does, only time advances (the particles
// keep their positions, at zero velocity). It wakes, and that step solves, when a pinned or held
// particle is to move, a collider moving near the particles' bounds (or enabled, disabled, set),
// or wake() from outside (grasp and release, set_state, reset, solver, cloth or friction
// parameters). One region, the whole scene: a cloth is one connected body, and a part of it at
// rest next to a moving part is pulled along at once.
bool Simulation::canSleepThrough() const {
  if (!asleep_ || inject_) return false;
  for (int i = 0; i < particles_.size(); ++i) {
    if (particles_.isKinematic(i) && particles_.kinematic_to[i] != particles_.position[i]) {
      return false;
    }
  }
  if (collisions_.colliderChanges() != sleep_collider_changes_) return false;
  return !collisions_.colliderMovesNear(sleep_lo_, sleep_hi_, sleep_margin_);
}

void Simulation::updateSleep(double dt) {
  const double limit = scene_.solver.sleep_speed;
  if (limit <= 0.0) return;
  // Where the stillness began: each particle's position then. still_from_ has the particles'
  // count from build(), so the assignment copies without allocating (a count changed since, by
  // a state set from outside, sizes it again).
  auto beginStillness = [this] {
    still_from_ = particles_.position;
    still_begun_ = true;
    still_time_ = 0.0;
  };
  if (!still_begun_ || still_from_.size() != particles_.position.size()) {
    beginStillness();
    return;
  }
  const double still_reach = limit * scene_.solver.sleep_time;
  double farthest_sq = 0.0;
  for (int i = 0; i < particles_.size(); ++i) {
    if (!particles_.isKinematic(i)) {
      farthest_sq = std::max(farthest_sq, (particles_.position[i] - still_from_[i]).squaredNorm());
    }
  }
  if (!(farthest_sq <= still_reach * still_reach)) {  // (a NaN is not still either)
    beginStillness();
    return;
  }
  still_time_ += dt;
  if (still_time_ + 1e-12 < scene_.solver.sleep_time || particles_.size() == 0) return;
  asleep_ = true;
  sleep_lo_ = sleep_hi_ = particles_.position[0];
  double reach = 0.0;
  for (int i = 0; i < particles_.size(); ++i) {
    if (!particles_.isKinematic(i)) particles_.velocity[i].setZero();
    sleep_lo_ = sleep_lo_.cwiseMin(particles_.position[i]);
    sleep_hi_ = sleep_hi_.cwiseMax(particles_.position[i]);
    reach = std::max(reach, particles_.radius[i]);
  }
  // Within twice the largest contact reach of the particles, a moving collider may touch them.
  sleep_margin_ = 2.0 * reach + 0.01;
  sleep_collider_changes_ = collisions_.colliderChanges();
}

void Simulation::wake() {
  asleep_ = false;
  still_begun_ = false;
  still_time_ = 0.0;
}

void Simulation::step(double dt) {
  stepHeld(dt);
  taut_chains_.release(particles_);  // the chains held for the step are free again
}

void Simulation::stepHeld(double dt) {
  if (asleep_) {
    followTrajectories(time_ + dt);
    followJointTrajectory(time_ + dt);
    moveRobotColliders();
    updateKinematicTargets(dt);
    if (canSleepThrough()) {
      for (GripperState& state : grippers_) state.pose = state.target;
      for (RobotLinkState& link : links_) link.pose = link.target;
      collisions_.endStep();  // colliders at their (unchanged) targets
      time_ += dt;
      ++slept_steps_;
      StepStats& stats = solver_.mutableStats();
      stats.sim_time += dt;
      stats.step_wall_time = stats.predict_time = stats.collide_time = 0.0;
      stats.project_time = stats.update_time = stats.contact_time = 0.0;
      stats.iterations = 0;
      stats.threads_used = 0;  // no solve
      stats.on_one_thread = false;
      last_step_restored_ = false;
      return;
    }
    wake();
    stepAwake(dt, /*targets_set=*/true);
    return;
  }
  stepAwake(dt, /*targets_set=*/false);
}

void Simulation::stepAwake(double dt, bool targets_set) {
  if (fault_recovery_) {
    std::copy(particles_.position.begin(), particles_.position.end(), good_position_.begin());
  }
  if (!targets_set) {
    followTrajectories(time_ + dt);
    followJointTrajectory(time_ + dt);
    moveRobotColliders();
    updateKinematicTargets(dt);
  }
  if (inject_ && injected_fault_ == InjectedFault::kNaN) injectFault(dt);
  solver_.step(dt, particles_, topology_, collisions_);
  if (inject_ && injected_fault_ == InjectedFault::kBlowUp) injectFault(dt);
  for (GripperState& state : grippers_) state.pose = state.target;
  for (RobotLinkState& link : links_) link.pose = link.target;
  time_ += dt;
  last_step_restored_ = false;
  if (fault_recovery_) {
    const StepFault fault = findFault();
    if (fault.kind != StepFault::Kind::kNone) undoStep(fault);
  }
  state_measured_ = false;
  if (!last_step_restored_) updateSleep(dt);
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
  StepFault fault;
  fault.time = time_;
  const double max_speed_sq = scene_.solver.max_speed * scene_.solver.max_speed;
  for (int i = 0; i < particles_.size(); ++i) {
    const Vec3& x = particles_.position[i];
    const Vec3& v = particles_.velocity[i];
    // One finiteness test for both: a sum of finite numbers is finite unless it overflows, and
    // any NaN or Inf term makes it non-finite.
    if (!std::isfinite(x.sum() + v.sum())) {
      fault.kind = StepFault::Kind::kNonFinite;
      fault.particle = i;
      return fault;
    }
    if (fault.kind == StepFault::Kind::kNone && !particles_.isKinematic(i) &&
        v.squaredNorm() > max_speed_sq) {
      // Keep looking: a non-finite particle further on is the worse news.
      fault.kind = StepFault::Kind::kTooFast;
      fault.particle = i;
      fault.speed = v.norm();
    }
  }
  return fault;
}

// The step could not stand: free particles back to the start of the step, at rest; kinematic ones
// keep the positions their grippers gave them (finite: every pose is checked on the way in).
void Simulation::undoStep(const StepFault& fault) {
  for (int i = 0; i < particles_.size(); ++i) {
    const bool keep = particles_.isKinematic(i) && std::isfinite(particles_.position[i].sum());
    if (!keep) particles_.position[i] = good_position_[i];
    particles_.velocity[i].setZero();
    particles_.substep_start[i] = particles_.position[i];
    particles_.step_start[i] = particles_.position[i];
  }
  ++restored_steps_;
  last_step_restored_ = true;
  last_fault_ = fault;
}

// A NaN goes in before the solver, which spreads it through the constraints. A blow-up goes in
// after it, as if the solver had produced it: a single fast particle going in would be pulled back
// by its zero-compliance links within the step (PBD's unconditional stability), testing nothing.
void Simulation::injectFault(double dt) {
  inject_ = false;
  for (int i = 0; i < particles_.size(); ++i) {
    if (particles_.isKinematic(i)) continue;
    if (injected_fault_ == InjectedFault::kNaN) {
      particles_.position[i].x() = std::numeric_limits<double>::quiet_NaN();
    } else {
      const Vec3 kick(1000.0 * scene_.solver.max_speed, 0.0, 0.0);
      particles_.velocity[i] += kick;
      particles_.position[i] += kick * dt;
    }
    return;
  }
}

std::string describe(const StepFault& fault, double max_speed) {
  std::ostringstream out;
  switch (fault.kind) {
    case StepFault::Kind::kNone:
      return "no fault";
    case StepFault::Kind::kNonFinite:
      out << "particle " << fault.particle << " not finite";
      break;
    case StepFault::Kind::kTooFast:
      out << "particle " << fault.particle << " at " << fault.speed << " m/s (solver.max_speed "
          << max_speed << " m/s)";
      break;
  }
  out << " at t = " << fault.time << " s";
  return out.str();
}

Metrics Simulation::computeMetrics() const {
  Metrics metrics;
  computeStrain(particles_, topology_, metrics.max_strain, metrics.mean_strain);
  computeStructuralStrain(particles_, topology_, metrics.structural_max_strain,
                          metrics.structural_mean_strain);
  metrics.max_penetration = collisions_.maxPenetration(particles_, topology_);
  metrics.finite = allFinite(particles_);
  // A diverged state has no meaningful geometry to intersect.
  metrics.self_intersections = metrics.finite ? countSelfIntersections(particles_, topology_) : -1;
  const Vec3& g = scene_.solver.gravity;
  for (int i = 0; i < particles_.size(); ++i) {
    if (particles_.isKinematic(i)) continue;
    metrics.kinetic_energy += 0.5 * particles_.mass[i] * particles_.velocity[i].squaredNorm();
    metrics.potential_energy -= particles_.mass[i] * g.dot(particles_.position[i]);
  }
  if (scene_.solver.method == Method::kMassSpring) {
    // Elastic energy of the explicit springs, so the baseline's energy is the full Hamiltonian.
    for (const DistanceConstraint& con : topology_.stretch) {
      const double stretch =
          (particles_.position[con.i] - particles_.position[con.j]).norm() - con.rest_length;
      metrics.potential_energy += 0.5 * scene_.solver.spring_stiffness * stretch * stretch;
    }
  }
  metrics.energy = metrics.kinetic_energy + metrics.potential_energy;
  return metrics;
}

}  // namespace pbd_cloth
