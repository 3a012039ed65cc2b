// Contact constraints of the collision seed, projected inside the solver loop as unilateral
// constraints C >= 0 (never as a post-pass): the bounds box (seed 000, C1), obstacles (plane,
// sphere, box, capsule; static or moving) with friction, particle-particle contact, and cloth
// self-collision with thickness (vertex-triangle per the seed, plus edge-edge; self_collision.h).
// Colliders are the scene's obstacles and the robot's link collision elements alike: one shape
// interface (shapes.h), each with its own pose, padding and friction.
// Position-level friction (seed eq. friction_correction) acts on all three kinds (contact.h).
//
// The step, as the solver drives it:
//   beginStep           broad phase at the step start (swept boxes, spatial hash, flat candidate
//                       arrays) and pre-stabilisation of overlaps that exist before the step
//   setSubstepFraction  obstacles at their interpolated poses for the substep
//   project             once per constraint pass: particle-particle, self-collision, obstacles,
//                       bounds (obstacles and bounds last: a pass ends free of penetration into
//                       them). The first pass of a substep first checks the predicted positions
//                       against their swept boxes and, if one left its box, runs the broad phase
//                       again (below), so contacts may be searched more than once per step
//   endStep             obstacles arrive at their targets
//
// No tunnelling, and how:
// - Obstacles: continuous. Each pass sweeps the particle's sphere along its substep path in the
//   obstacle's frame (from substep_start under the substep's begin pose to the position under its
//   end pose; shapes.h sweepSphere). If the path enters the shape and the end point's nearest face
//   is not the one it entered by (a thin plate crossed, a box corner cut), the particle is
//   projected onto the tangent plane at the entry point, i.e. back to the side it came from;
//   otherwise onto the nearest surface. A moving obstacle therefore sweeps particles along however
//   fast it moves, and a particle of any speed never passes a plate of any thickness. (Contact is
//   per particle: an obstacle thinner than the gap between two cloth particles can slip between
//   them.)
// - Particles and cloth: the broad phase bounds each particle's motion over the search window
//   (below; at most the step) by its swept box (its position to the unconstrained prediction
//   x + v T + g T^2 at the window's end, grown by half its radius) and, for self-collision, by
//   its reference path (a straight line to its free flight at the window's end, left by at most
//   the same half radius), which lets the search drop pairs that stay apart however the boxes
//   overlap (SelfCollision::findPairs). After each substep's prediction the particles are checked
//   against both; if one left its box or path the particle-particle and vertex-triangle
//   candidates are searched again for the rest of the window (edge-edge candidates, a safety net
//   behind vertex-triangle, stay those of the window's start). A contact found again keeps its
//   state (friction window, its base point and the depth resolved in it; a self-contact's side),
//   so the search changes nothing for it. Self-contacts keep each vertex (edge) on the side of
//   the triangle (edge) it was on, so a vertex pushed through a cloth layer is pulled back, never
//   out of the far side.
// - The search window: a search covers the next few substeps, not always the whole step, and
//   the first substep of each window searches again (edge-edge pairs too). Long windows search
//   less often; short ones list fewer pairs, since a pair is listed when the window's motion can
//   bring it within reach: where neighbours move apart fast (a corner whipping round a ball) the
//   candidates grow with the window's length squared. solver.search_window fixes the window; 0,
//   the default, chooses it per step (Collisions::endStep). A search costs about a pass over the
//   particles (the tree's refit and traversal); a far candidate (its boxes more than a few
//   thicknesses apart at a substep's start, SelfCollision::takeFarPairSubsteps), listed for the
//   window's motion and not for its nearness, costs a check in every substep of its window. So
//   after a step whose far candidates, summed over its substeps, came to more than
//   kWindowHalves times the particles times its searches, the window halves; below
//   kWindowDoubles times that, it doubles, up to the whole step. Near candidates do not count:
//   layers lying on each other list them whatever the window. A cloth moving as a whole keeps
//   the whole step (fabric_table: no far candidate); the drape at 64 x 64 goes down to 2
//   substeps after its corners meet the ball.
// - Initial overlaps: at each step start, pre-stabilisation separates contacts overlapping by more
//   than a slop by at most max_separation_speed * dt, on positions before the prediction, so the
//   separation adds no velocity (Macklin et al. 2014, sec. 4.4). What remains is only kept from
//   growing during the step, so particles that start overlapping never pop apart.
#pragma once

#include <vector>

#include "pbd_cloth/collision/collider.h"
#include "pbd_cloth/collision/collider_snapshot.h"
#include "pbd_cloth/collision/contact.h"
#include "pbd_cloth/collision/particle_contacts.h"
#include "pbd_cloth/collision/path_boxes.h"
#include "pbd_cloth/collision/self_collision.h"
#include "pbd_cloth/geometry/shapes.h"
#include "pbd_cloth/model/particles.h"
#include "pbd_cloth/parallel/worker_pool.h"

namespace pbd_cloth {

// Figures of the last step.
struct CollisionStats {
  int particle_pairs = 0;         // particle-particle candidates
  int vertex_triangle_pairs = 0;  // self-collision candidates: a vertex near a triangle
  int edge_edge_pairs = 0;        // self-collision candidates: two edges near each other
  int broad_phase_runs = 0;       // whole searches: 1, plus one per new window and per substep
                                  // where too many particles left their bounds for a local one
  int local_searches = 0;         // searches for a few particles that left their bounds
                                  // (SelfCollision::findPairsNear), not counted above
  int search_window = 0;          // substeps one search covered (solver.search_window)
  int truncated_searches = 0;     // self-collision searches of the last step that stopped at
                                  // their budget (SelfCollision::kPairsPerElement): a cloth
                                  // crushed into itself, candidates skipped
};

class Collisions {
 public:
  // Bounds, friction, thickness, self-collision, gravity (for the motion bound) and the scene's
  // colliders (sim/colliders.h collisionSettings makes them from the scene).
  void configure(const CollisionSettings& settings);
  // One more collider after the scene's obstacles (a robot link's collision element, its pose in
  // the scene frame); returns its index. Call before prepare().
  int addCollider(const Collider& collider);
  // cloth.friction: every collider without a friction of its own.
  void setFriction(const Friction& friction);
  // A collider moves from its current pose to `target` over the next step (a kinematic body).
  // A non-finite target is refused (returns false) and the collider keeps its course.
  bool setObstacleTarget(int obstacle, const Pose& target);
  // A disabled collider touches nothing. Enabled again, it is placed at its next target without
  // sweeping the way in between (it was not followed while away).
  void setObstacleEnabled(int obstacle, bool enabled);
  bool obstacleEnabled(int obstacle) const { return enabled_[obstacle] != 0; }
  // Every collider: the scene's obstacles first, then those added.
  const std::vector<Collider>& obstacles() const { return obstacles_; }
  // Sizes every buffer (called once the particles exist) and finds the contacts of the initial
  // state, so maxPenetration() is right before the first step.
  void prepare(const Particles& particles, const ClothTopology& topology);

  // Before each step: a contact search covers `window` substeps of the step's `substeps`
  // (solver.search_window; 0: chosen from the steps before, "The search window" above).
  void setSearchWindow(int window, int substeps);
  // The window the adaptive rule holds for the next step (substeps; 0 before its first step). Part
  // of a saved state (saved_state.h), so a saved run continues bit for bit.
  int adaptiveSearchWindow() const { return adaptive_window_; }
  void setAdaptiveSearchWindow(int window) { adaptive_window_ = window; }
  // Once per step, before the substeps. Moves particles only to pre-stabilise initial overlaps
  // (and then sets step_start to the result).
  void beginStep(Particles& particles, const ClothTopology& topology, double dt);
  // Obstacles at fractions [s_begin, s_end] of the step for the next substep.
  void setSubstepFraction(double s_begin, double s_end);
  // One pass over every contact constraint; returns the largest position change.
  double project(Particles& particles, const ClothTopology& topology);
  // Whether project() reads or moves no particle: no obstacle, no bounds, no particle-particle
  // contacts and no self-collision (a cloth swinging free). The solver may then keep the positions
  // out of `particles` during the passes (Solver::linksAlone).
  bool touchesNoParticle(const Particles& particles, const ClothTopology& topology) const {
    return shapes_.empty() && !bounds_.enabled && !particleContactsActive(particles) &&
           !selfCollisionActive(topology);
  }
  // Ends the step: obstacles arrive at their targets.
  void endStep();
  // A step run again from its start (sim/accuracy_controller.h): what beginStep .. endStep
  // change across steps (the obstacles' poses, the step's stamp, the adaptive search window) is
  // saved before its first attempt and restored before the next. Allocates nothing after the
  // first.
  void rememberStepStart();
  void restoreStepStart();
  // Between steps: contact lists that an extreme step grew beyond their reserve go back to it
  // (SelfCollision::releaseExcessCapacity). Returns the bytes released.
  std::size_t releaseExcessCapacity();

  // Deepest violation of any contact constraint in the current positions (m): particle inside an
  // obstacle (radius minus distance), particle pair overlap, vertex closer than h to a triangle.
  double maxPenetration(const Particles& particles, const ClothTopology& topology) const;
  // Free particles deeper than `slack` (m) inside each enabled collider: inside[k] of them, the
  // first first_inside[k] (-1: none). For the start-up warning about an overlapping start.
  void countInside(const Particles& particles, double slack, std::vector<int>& inside,
                   std::vector<int>& first_inside) const;

  // Saving and restoring a state (state/saved_state.h; collider_snapshot.h): a collider's pose,
  // target and flags (the name is left to the caller), and the mesh colliders' per-contact search
  // caches.
  void getColliderState(int collider, BodySnapshot& body) const;
  void setColliderState(int collider, const BodySnapshot& body);
  void getMeshContacts(std::vector<MeshContactCache>& caches) const;
  // Every cache as listed, the others as never queried (the caller checked the indices).
  void setMeshContacts(const std::vector<MeshContactCache>& caches);
  // After the particles were replaced by a saved state: the contact candidates of the new
  // positions, as prepare() finds them, so maxPenetration() is right before the next step. The
  // stamps keep counting up, so no contact state of before can pass for a current one.
  void findCandidatesNow(const Particles& particles, const ClothTopology& topology);

  // Sleeping (Simulation::step): whether a collider moves this step (its target differs from its
  // pose) with its swept bounds within [lo, hi] grown by margin, or was enabled, disabled or
  // replaced since the count `changes` was read.
  bool colliderMovesNear(const Vec3& lo, const Vec3& hi, double margin) const;
  long colliderChanges() const { return collider_changes_; }

  const CollisionStats& stats() const { return stats_; }
  // Sum over the step's passes of each particle-particle and self-contact's multiplier times its
  // gradient at the kinematic particles it touches (kg m; zero elsewhere): what the contact would
  // have moved them by, times their mass. The solver turns it into their constraint force.
  // (Obstacles and bounds leave kinematic particles alone.)
  const Vec3Array& kinematicReaction() const { return kinematic_reaction_; }
  // Threads for the obstacle and bounds projection (the solver's, solver.threads; nullptr: this
  // thread alone), in ranges of particles: the same result for every count.
  void setWorkerPool(WorkerPool* pool) { pool_ = pool; }
  // Largest speed at which pre-existing overlaps are separated (m/s), 1 by default.
  void setMaxSeparationSpeed(double speed) { max_separation_speed_ = speed; }

 private:
  // Swept boxes over box_time from now, and reference paths over path_time from now, the
  // particles' positions being those of fraction `fraction` of the step.
  void computeSweptBoxes(const Particles& particles, double box_time, double path_time,
                         double fraction);
  // `step_start`: the step's first search (no contact state to carry); `window_start`: a new
  // search window (edge-edge pairs searched as well).
  void findCandidates(const Particles& particles, const ClothTopology& topology, bool step_start,
                      bool window_start);
  // Whether a particle left its swept box or (with `paths`: self-collision is active) a cloth
  // particle its reference path: the search's candidates then no longer cover every contact.
  // Lists them in leavers_, up to kMaxLocalLeavers of every 1024 particles and one more (then
  // too many for a local search); returns how many it listed.
  int leftMotionBounds(const Particles& particles, bool paths);
  // Particle i's swept box and reference path (computeSweptBoxes), `mid_step` after predict().
  void sweepParticle(const Particles& particles, int i, double box_time, double path_time,
                     bool mid_step);
  // The search within a window when only the particles of leavers_ left their bounds: every path
  // re-expressed from this substep's end, theirs set anew, and only their part of the
  // self-collision candidates searched again (SelfCollision::findPairsNear).
  void searchNear(const Particles& particles, const ClothTopology& topology);
  void preStabilizeObstacles(Particles& particles, double max_shift);
  // first_pass: the substep's first pass, in which no contact has pushed yet.
  double projectObstaclesAndBounds(Particles& particles, bool first_pass);
  // The substep's first pass of obstacles and bounds over the free particles [begin, end), at
  // most kCullBlock of them, culled by their paths' boxes (`near`: room for the obstacles'
  // list); returns the largest correction.
  double projectBlockFirstPass(Particles& particles, int begin, int end, int* near);
  int listNearObstacles(const Eigen::Array3d& lo, const Eigen::Array3d& hi, bool every,
                        int* near) const;
  // The obstacles' contacts of free particle i (first_pass: the substep's first pass): those of
  // `near` (near_count of them, increasing), and after the first contact that moves the particle
  // every later obstacle, since its path may then reach bounds its block's paths kept out of;
  // every obstacle when `near` is nullptr. kFirstReaches: the caller found the particle's path
  // box reaching the first listed obstacle's bounds (the test is not repeated).
  template <bool kFirstReaches>
  double projectObstaclesOn(Particles& particles, int i, bool first_pass, const int* near,
                            int near_count);
  // True when free particle x (substep start `start`, radius r) surely stays clear of obstacle
  // k, a shape that does not move in this substep, by its bounding ball: the exact test of
  // projectObstaclesOn would skip it too.
  bool clearOfStillShape(int k, const Vec3& x, const Vec3& start, double r) const;
  // True when x lies farther than `reach` from obstacle k's bounding ball (boundingRadius about
  // its frame at the substep's end), by a margin far above rounding: its distance to the
  // shape is then larger than reach as computed.
  bool outsideBoundingBall(const Vec3& x, double reach, int k) const;
  // The bounds' clamp of a free particle's position.
  double projectBoundsOn(Vec3& x) const;
  bool particleContactsActive(const Particles& particles) const;
  bool selfCollisionActive(const ClothTopology& topology) const;

  ParticleBounds bounds_;
  Friction friction_;
  double thickness_ = 0.005;
  bool self_collision_ = false;
  Vec3 gravity_ = Vec3(0.0, 0.0, -9.81);
  double max_separation_speed_ = 1.0;

  // Obstacles: collider and pose at the end of the last step, target of this step, and the
  // local shapes and frames of the current substep.
  std::vector<Collider> obstacles_;
  std::vector<Pose> obstacle_targets_;
  std::vector<Shape> shapes_;
  std::vector<Friction> obstacle_friction_;
  std::vector<char> enabled_;
  std::vector<char> teleport_;  // enabled again: jump to the next target
  long collider_changes_ = 0;   // enabled, disabled or state set: counted for sleeping
  std::vector<Frame> frame_begin_;
  std::vector<Frame> frame_end_;
  // The shape stays put this substep (frame_begin_ == frame_end_) and takes the bounding-ball
  // cull (ball_cull_: not a box or a plane): clearOfStillShape applies.
  std::vector<char> still_;
  std::vector<char> ball_cull_;
  std::vector<double> bound_radius_;  // boundingRadius of each shape
  Vec3Array obstacle_lo_;  // world bounds of each obstacle over the substep (begin and end poses)
  Vec3Array obstacle_hi_;
  // Each (particle, obstacle) pair's state, obstacle by obstacle: slot obstacle * particles +
  // particle (slotOf), so that the particles near one obstacle, neighbours in the cloth, share
  // cache lines and pages. Particle by particle, a cloth of 16384 particles over 18 obstacles
  // (33 MB of states) had each particle's slots 2 KB after the last one's.
  std::size_t slotOf(int particle, std::size_t obstacle) const {
    return obstacle * static_cast<std::size_t>(slot_particles_) +
           static_cast<std::size_t>(particle);
  }
  int slot_particles_ = 0;
  std::vector<ContactState> obstacle_contacts_;
  std::vector<double> obstacle_allowance_;  // same layout: allowanceFor, this step
  std::vector<char> has_allowance_;         // per particle: a slot of obstacle_allowance_ not zero
  std::vector<int> mesh_hint_;  // same layout: last closest triangle (mesh shapes' search hint)
  // Same layout, mesh shapes: the last distance computed and where (local frame), a free lower
  // bound on the next one.
  std::vector<double> mesh_distance_;
  Vec3Array mesh_point_;

  // Step and substep.
  double dt_ = 0.0;
  double substep_begin_ = 0.0;
  int step_ = 0;              // stamp of the current step (ContactState::window)
  int substep_ = 0;           // stamp of the current substep (ContactState::substep)
  int checked_substep_ = -1;  // substep whose particles were checked against their swept boxes

  // Broad phase of the step.
  Vec3Array box_lo_;  // swept box of each particle over the (rest of the) step
  Vec3Array box_hi_;
  // The second motion bound (self-collision): each particle's reference path, a straight line
  // from path_start_ (where it was at the search, fraction path_fraction_ of the step) to
  // path_start_ + path_move_ (its free flight to the step end), which it may leave by at most
  // kBoxSlack times its radius while the search stands.
  Vec3Array path_start_;
  Vec3Array path_move_;
  double path_fraction_ = 0.0;
  std::vector<int> leavers_;  // leftMotionBounds
  // The search window: the setting (0: adaptive), the substeps of a step, the window of this
  // step (substeps, and as a fraction of the step) and the fraction at which the current one ends.
  int window_setting_ = 0;
  int substeps_ = 1;
  int window_substeps_ = 1;
  double window_fraction_ = 1.0;
  double window_end_ = 1.0;
  // The adaptive rule: its window for the next step, and this step's searches.
  int adaptive_window_ = 0;
  std::vector<Pose> start_pose_;  // rememberStepStart
  int start_step_ = 0;
  int start_window_ = 0;
  int searches_in_step_ = 0;
  double substep_end_ = 0.0;
  ParticleContacts particle_contacts_;
  SelfCollision self_collision_pairs_;
  WorkerPool* pool_ = nullptr;
  // solver.threads is at most 64 (config/scene_config.cpp validate).
  static constexpr int kMaxThreads = 64;
  // Largest change of each thread's range.
  double thread_max_change_[kMaxThreads] = {};
  // projectBlockFirstPass's lists, one of obstacles_.size() entries for each thread.
  std::vector<int> near_obstacles_;
  std::vector<PathBox> near_boxes_;  // their bounds, the same slots (reachedObstacles)
  // The loop that computes a block's path boxes (path_boxes.h): the processor's best within
  // solver.simd and solver.avx512.
  PathBoxKernel path_box_kernel_ = PathBoxKernel::kPortable;
  CollisionStats stats_;
  Vec3Array kinematic_reaction_;
};

}  // namespace pbd_cloth
