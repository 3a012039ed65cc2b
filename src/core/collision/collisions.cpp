#include "pbd_cloth/collision/collisions.h"

#include <algorithm>
#include <climits>
#include <cmath>
#include <limits>

namespace pbd_cloth {

namespace {

// Overlaps deeper than this fraction of the contact distance at a step start are pre-existing:
// pre-stabilised and, as far as the shift cap leaves them, kept from growing rather than projected
// away during the step (allowanceFor in contact.h). The residual overlap of a loaded stack, which
// the projection and its friction handle, stays below it.
constexpr double kOverlapSlop = 0.02;
// Obstacle contacts go to threads only with at least this many particles for each.
constexpr int kParticlesPerThread = 512;
// Swept boxes grow by this fraction of the particle radius to absorb the difference between the
// unconstrained prediction and the constrained motion.
constexpr double kBoxSlack = 0.5;
// The adaptive search window halves above this many far candidates (summed over the step's
// substeps) per particle and search, and doubles below the second. Chosen on the drape from
// 32 x 32 to 128 x 128 and fabric_table: 1 and 1/4 kept windows too long on the drape (64 x 64:
// 21.8 against 18.0 ms a step with these), fabric_table keeps the whole step with any of them
// (doc/journal.md, "Search windows").
constexpr double kWindowHalves = 0.1;
constexpr double kWindowDoubles = 0.025;
// The obstacles' first pass culls particles in blocks of this many consecutive indices (part of a
// grid's row) before it culls them one by one: an obstacle that a block's paths keep out of costs
// the block one box test instead of one per particle (a robot's links, far from most of the
// cloth: doc/journal.md, "2026-11-28: Obstacles culled in blocks").
constexpr int kCullBlock = 32;
// A local search (Collisions::searchNear) for at most this many leavers per 1024 particles; more,
// and a whole search costs less: each leaver renews its leaves, refits their paths to the root and
// traverses them against the tree, several times a whole search's cost per particle. 32 rather
// than 64: the drape 1.49 to 1.34 ms a step, the drape tiled to 128 x 128 18.8 to 14.5 ms, the
// rest the same; with 16 and 24 three particles of the resting T-shirt took turns moving a few
// micrometres a step, which kept it awake while sleep went by velocity. doc/journal.md,
// "2026-11-27: Local searches" and "Sleeping".
constexpr int kMaxLocalLeavers = 32;
int mostLocalLeavers(int particles) { return kMaxLocalLeavers * particles / 1024; }

// True when a sphere of radius r at x lies wholly outside the box [lo, hi]: it cannot touch a
// shape inside that box.
bool outsideBounds(const Vec3& x, double r, const Vec3& lo, const Vec3& hi) {
  return (x.array() + r < lo.array()).any() || (x.array() - r > hi.array()).any();
}

// True when the boxes [a_lo, a_hi] and [b_lo, b_hi] share no point.
bool boxesApart(const Eigen::Array3d& a_lo, const Eigen::Array3d& a_hi, const Vec3& b_lo,
                const Vec3& b_hi) {
  return (a_hi < b_lo.array()).any() || (a_lo > b_hi.array()).any();
}

}  // namespace

void Collisions::configure(const CollisionSettings& settings) {
  bounds_ = settings.bounds;
  friction_ = settings.friction;
  thickness_ = settings.thickness;
  self_collision_ = settings.self_collision;
  gravity_ = settings.gravity;
  path_box_kernel_ = bestPathBoxKernel(settings.simd, settings.avx512);
  obstacles_.clear();
  obstacle_targets_.clear();
  shapes_.clear();
  obstacle_friction_.clear();
  enabled_.clear();
  teleport_.clear();
  frame_begin_.clear();
  frame_end_.clear();
  still_.clear();
  ball_cull_.clear();
  bound_radius_.clear();
  obstacle_lo_.clear();
  obstacle_hi_.clear();
  for (const Collider& collider : settings.colliders) addCollider(collider);
}

int Collisions::addCollider(const Collider& collider) {
  ++collider_changes_;
  obstacles_.push_back(collider);
  obstacle_targets_.push_back(collider.pose);
  shapes_.push_back(collider.shape);
  obstacle_friction_.push_back(collider.has_friction ? collider.friction : friction_);
  enabled_.push_back(1);
  teleport_.push_back(0);
  frame_begin_.push_back(frameFromPose(collider.pose));
  frame_end_.push_back(frame_begin_.back());
  // A box's or a plane's bounds already hold it as closely as a ball would (an upright box's
  // are the box): no ball cull for them, which would only add its cost to every contact.
  const ShapeType type = shapes_.back().type;
  ball_cull_.push_back(type != ShapeType::kBox && type != ShapeType::kPlane);
  still_.push_back(ball_cull_.back());
  bound_radius_.push_back(boundingRadius(shapes_.back()));
  obstacle_lo_.push_back(Vec3::Zero());
  obstacle_hi_.push_back(Vec3::Zero());
  return static_cast<int>(obstacles_.size()) - 1;
}

void Collisions::setFriction(const Friction& friction) {
  friction_ = friction;
  for (std::size_t k = 0; k < obstacles_.size(); ++k) {
    if (!obstacles_[k].has_friction) obstacle_friction_[k] = friction;
  }
}

bool Collisions::setObstacleTarget(int obstacle, const Pose& target) {
  if (!target.position.allFinite() || !target.orientation.coeffs().allFinite() ||
      target.orientation.norm() == 0.0) {
    return false;
  }
  obstacle_targets_[obstacle].position = target.position;
  obstacle_targets_[obstacle].orientation = target.orientation.normalized();
  if (teleport_[obstacle]) {
    obstacles_[obstacle].pose = obstacle_targets_[obstacle];
    teleport_[obstacle] = 0;
  }
  return true;
}

bool Collisions::colliderMovesNear(const Vec3& lo, const Vec3& hi, double margin) const {
  const Vec3 near_lo = lo - Vec3::Constant(margin), near_hi = hi + Vec3::Constant(margin);
  for (std::size_t k = 0; k < obstacles_.size(); ++k) {
    if (!enabled_[k]) continue;
    const Pose& from = obstacles_[k].pose;
    const Pose& to = obstacle_targets_[k];
    if (from.position == to.position && from.orientation.coeffs() == to.orientation.coeffs()) {
      continue;
    }
    Vec3 a_lo, a_hi, b_lo, b_hi;
    worldBounds(shapes_[k], interpolateFrame(from, to, 0.0), a_lo, a_hi);
    worldBounds(shapes_[k], interpolateFrame(from, to, 1.0), b_lo, b_hi);
    const Vec3 swept_lo = a_lo.cwiseMin(b_lo), swept_hi = a_hi.cwiseMax(b_hi);
    if ((swept_lo.array() <= near_hi.array()).all() &&
        (near_lo.array() <= swept_hi.array()).all()) {
      return true;
    }
  }
  return false;
}

void Collisions::setObstacleEnabled(int obstacle, bool enabled) {
  if ((enabled_[obstacle] != 0) != enabled) ++collider_changes_;
  if (enabled && !enabled_[obstacle]) teleport_[obstacle] = 1;
  enabled_[obstacle] = enabled ? 1 : 0;
}

void Collisions::prepare(const Particles& particles, const ClothTopology& topology) {
  const int n = particles.size();
  slot_particles_ = n;
  obstacle_contacts_.assign(static_cast<std::size_t>(n) * obstacles_.size(), ContactState());
  has_allowance_.assign(n, 0);
  obstacle_allowance_.assign(obstacle_contacts_.size(), 0.0);
  mesh_hint_.assign(obstacle_contacts_.size(), -1);
  mesh_distance_.assign(obstacle_contacts_.size(), -std::numeric_limits<double>::infinity());
  mesh_point_.assign(obstacle_contacts_.size(), Vec3::Zero());
  near_obstacles_.assign(static_cast<std::size_t>(kMaxThreads) * obstacles_.size(), 0);
  near_boxes_.assign(near_obstacles_.size(), PathBox());
  box_lo_.assign(n, Vec3::Zero());
  box_hi_.assign(n, Vec3::Zero());
  kinematic_reaction_.assign(n, Vec3::Zero());
  leavers_.clear();
  leavers_.reserve(mostLocalLeavers(n) + 1);
  particle_contacts_.reserve(particles);
  self_collision_pairs_.reserve(particles, topology);
  substep_ = step_ = 0;
  checked_substep_ = -1;
  dt_ = 0.0;
  stats_ = CollisionStats();
  path_start_.assign(n, Vec3::Zero());
  path_move_.assign(n, Vec3::Zero());
  computeSweptBoxes(particles, 0.0, 0.0, 0.0);
  findCandidates(particles, topology, true, true);
}

bool Collisions::particleContactsActive(const Particles& particles) const {
  return particles.size() > particles.cloth_count;
}

bool Collisions::selfCollisionActive(const ClothTopology& topology) const {
  return self_collision_ && topology.triangleCount() > 0;
}

// The motion bounds of the broad phase.
// The swept box: from where the particle is to its unconstrained prediction box_time later
// (x + v T + g T^2, above the substepped free flight x + v T + g T^2 (1 + 1/n) / 2), grown by half
// the radius for the constraints' deviation from it. Kinematic particles move exactly to their
// prescribed target. After predict() the substep start is included as well.
// The reference path (self-collision's distance cull, SelfCollision::findPairs): the straight
// line from x to its free flight x + v T + g T^2 / 2 path_time later (a kinematic particle's own
// straight line to its target), left by at most the same half radius. A box bounds where a
// particle may go, the path how it may move relative to its neighbours: a cloth falling or
// swinging as a whole moves its neighbours along the same paths, so a vertex and the triangles
// around it, which every box search lists (a right triangle's box holds the opposite corner of
// the next one), are culled by their distance now.
void Collisions::computeSweptBoxes(const Particles& p, double box_time, double path_time,
                                   double fraction) {
  const bool mid_step = checked_substep_ >= 0;
  path_fraction_ = fraction;
  for (int i = 0; i < p.size(); ++i) sweepParticle(p, i, box_time, path_time, mid_step);
}

void Collisions::sweepParticle(const Particles& p, int i, double box_time, double path_time,
                               bool mid_step) {
  const Vec3& x = p.position[i];
  Vec3 end;
  double slack = 0.0;
  if (p.inverse_mass[i] == 0.0) {
    end = p.kinematic_to[i];
    path_move_[i] = p.kinematic_to[i] - x;
  } else {
    end = x + box_time * p.velocity[i] + (box_time * box_time) * gravity_;
    slack = kBoxSlack * p.radius[i];
    path_move_[i] = path_time * p.velocity[i] + (0.5 * path_time * path_time) * gravity_;
  }
  path_start_[i] = x;
  Vec3 lo = x.cwiseMin(end), hi = x.cwiseMax(end);
  if (mid_step) {
    lo = lo.cwiseMin(p.substep_start[i]);
    hi = hi.cwiseMax(p.substep_start[i]);
  }
  box_lo_[i] = lo.array() - slack;
  box_hi_[i] = hi.array() + slack;
}

void Collisions::searchNear(const Particles& p, const ClothTopology& topology) {
  // The paths of the particles that kept their bounds from this substep's end on: the same
  // lines, so each particle's bound is unchanged, and all paths share the fraction they start
  // from, as the cull needs (SelfCollision::findPairs: s the same for all).
  const double span = window_end_ - path_fraction_;
  const double along = span > 0.0 ? std::min(1.0, (substep_end_ - path_fraction_) / span) : 1.0;
  for (int i = 0; i < p.size(); ++i) {
    path_start_[i] += along * path_move_[i];
    path_move_[i] *= 1.0 - along;
  }
  path_fraction_ = substep_end_;
  const std::vector<int>& renewed =
      self_collision_pairs_.renewedAround(leavers_, topology, p.cloth_count);
  for (int i : renewed) {
    sweepParticle(p, i, (window_end_ - substep_begin_) * dt_, (window_end_ - substep_end_) * dt_,
                  true);
  }
  const MotionBounds bounds{box_lo_, box_hi_, path_start_, path_move_, kBoxSlack};
  self_collision_pairs_.findPairsNear(p, topology, bounds, thickness_, renewed);
  stats_.vertex_triangle_pairs = self_collision_pairs_.vertexTrianglePairCount();
  if (self_collision_pairs_.lastSearchTruncated()) ++stats_.truncated_searches;
  ++stats_.local_searches;
}

void Collisions::findCandidates(const Particles& particles, const ClothTopology& topology,
                                bool step_start, bool window_start) {
  if (particleContactsActive(particles)) {
    particle_contacts_.findPairs(particles, box_lo_, box_hi_, !step_start);
  }
  if (selfCollisionActive(topology)) {
    const MotionBounds bounds{box_lo_, box_hi_, path_start_, path_move_, kBoxSlack};
    self_collision_pairs_.findPairs(particles, topology, bounds, thickness_, window_start,
                                    !step_start);
  }
  stats_.particle_pairs = particle_contacts_.pairCount();
  const bool self_collision = selfCollisionActive(topology);
  stats_.vertex_triangle_pairs =
      self_collision ? self_collision_pairs_.vertexTrianglePairCount() : 0;
  stats_.edge_edge_pairs = self_collision ? self_collision_pairs_.edgeEdgePairCount() : 0;
  if (self_collision && self_collision_pairs_.lastSearchTruncated()) ++stats_.truncated_searches;
  ++stats_.broad_phase_runs;
  ++searches_in_step_;
}

int Collisions::leftMotionBounds(const Particles& p, bool paths) {
  leavers_.clear();
  const int most = mostLocalLeavers(p.size());
  // The predicted positions are those of the substep's end: that far along the reference paths.
  const double span = window_end_ - path_fraction_;
  const double along = span > 0.0 ? std::min(1.0, (substep_end_ - path_fraction_) / span) : 1.0;
  for (int i = 0; i < p.size(); ++i) {
    const Vec3& x = p.position[i];
    bool left =
        !((x.array() >= box_lo_[i].array()).all() && (x.array() <= box_hi_[i].array()).all());
    if (!left && paths && i < p.cloth_count) {
      const Vec3 off_path = x - (path_start_[i] + along * path_move_[i]);
      const double deviation = kBoxSlack * p.radius[i];
      left = off_path.squaredNorm() > deviation * deviation;
    }
    if (!left) continue;
    leavers_.push_back(i);
    if (static_cast<int>(leavers_.size()) > most) break;
  }
  return static_cast<int>(leavers_.size());
}

void Collisions::beginStep(Particles& particles, const ClothTopology& topology, double dt) {
  dt_ = dt;
  ++step_;
  stats_.broad_phase_runs = 0;
  stats_.local_searches = 0;
  stats_.truncated_searches = 0;
  checked_substep_ = -1;
  std::fill(kinematic_reaction_.begin(), kinematic_reaction_.end(), Vec3::Zero());
  for (std::size_t k = 0; k < obstacles_.size(); ++k) {
    frame_begin_[k] = frame_end_[k] = frameFromPose(obstacles_[k].pose);
    still_[k] = ball_cull_[k];
  }
  const bool particle_contacts = particleContactsActive(particles);
  const bool self_collision = selfCollisionActive(topology);
  window_substeps_ = window_setting_ > 0    ? window_setting_
                     : adaptive_window_ > 0 ? adaptive_window_
                                            : substeps_;
  window_substeps_ = std::max(1, std::min(substeps_, window_substeps_));
  window_fraction_ = static_cast<double>(window_substeps_) / substeps_;
  window_end_ = window_fraction_;
  stats_.search_window = window_substeps_;
  self_collision_pairs_.takeFarPairSubsteps();
  searches_in_step_ = 0;
  if (particle_contacts || self_collision) {
    computeSweptBoxes(particles, window_end_ * dt, window_end_ * dt, 0.0);
    findCandidates(particles, topology, true, true);
  }
  // Overlaps the step starts with are separated here, before predict() copies the positions into
  // substep_start, so the separation is no velocity (Macklin et al. 2014, sec. 4.4).
  const double max_shift = max_separation_speed_ * dt;
  if (particle_contacts) particle_contacts_.preStabilize(particles, max_shift, kOverlapSlop);
  if (self_collision) {
    self_collision_pairs_.preStabilize(particles, thickness_, max_shift, kOverlapSlop);
  }
  preStabilizeObstacles(particles, max_shift);
  particles.step_start = particles.position;
  if (particle_contacts) {
    particle_contacts_.measureAllowances(particles, particles.step_start, kOverlapSlop);
  }
  if (self_collision) {
    self_collision_pairs_.measureAllowances(particles.step_start, thickness_, kOverlapSlop);
  }
}

void Collisions::setSubstepFraction(double s_begin, double s_end) {
  if (substep_ == INT_MAX) {
    // Stamps wrap after 2^31 substeps (weeks of running): forget every state, none is current.
    substep_ = step_ = 0;
    for (ContactState& state : obstacle_contacts_) state.forget();
  }
  ++substep_;
  substep_begin_ = s_begin;
  substep_end_ = s_end;
  for (std::size_t k = 0; k < obstacles_.size(); ++k) {
    frame_begin_[k] = interpolateFrame(obstacles_[k].pose, obstacle_targets_[k], s_begin);
    frame_end_[k] = interpolateFrame(obstacles_[k].pose, obstacle_targets_[k], s_end);
    still_[k] = ball_cull_[k] && frame_begin_[k].rotation == frame_end_[k].rotation &&
                frame_begin_[k].translation == frame_end_[k].translation;
    Vec3 lo, hi;
    worldBounds(shapes_[k], frame_begin_[k], obstacle_lo_[k], obstacle_hi_[k]);
    worldBounds(shapes_[k], frame_end_[k], lo, hi);
    obstacle_lo_[k] = obstacle_lo_[k].cwiseMin(lo);
    obstacle_hi_[k] = obstacle_hi_[k].cwiseMax(hi);
  }
}

double Collisions::project(Particles& particles, const ClothTopology& topology) {
  const bool particle_contacts = particleContactsActive(particles);
  const bool self_collision = selfCollisionActive(topology);
  const bool first_pass = checked_substep_ != substep_;
  if (first_pass) {
    // First pass of a substep: the prediction is done. A new window searches; so does a particle
    // outside its swept box, which may meet contacts the search did not list (for the rest of
    // the window).
    checked_substep_ = substep_;
    // The window's end, within rounding of a substep's end: a window whose end is this
    // substep's start has run out.
    const double rounding = 1e-9;
    const bool window_over = substep_begin_ > window_end_ - rounding;
    if (window_over) window_end_ = std::min(1.0, substep_begin_ + window_fraction_);
    if (window_end_ < substep_end_ + rounding) window_end_ = substep_end_;
    const int leavers = (particle_contacts || self_collision) && !window_over
                            ? leftMotionBounds(particles, self_collision)
                            : 0;
    if ((particle_contacts || self_collision) && (window_over || leavers > 0)) {
      // A few cloth particles off their bounds search again alone (a pass over the cloth for
      // each would make the searches of a step grow with the cloth: doc/journal.md, "2026-11-27:
      // Local searches"); many, a new window, or particle-particle contacts, whose broad phase has
      // no local form, the whole search.
      if (!window_over && self_collision && !particle_contacts &&
          leavers <= mostLocalLeavers(particles.size())) {
        searchNear(particles, topology);
      } else {
        computeSweptBoxes(particles, (window_end_ - substep_begin_) * dt_,
                          (window_end_ - substep_end_) * dt_, substep_end_);
        findCandidates(particles, topology, false, window_over);
      }
      if (particle_contacts) {
        particle_contacts_.measureAllowances(particles, particles.step_start, kOverlapSlop);
      }
      if (self_collision) {
        self_collision_pairs_.measureAllowances(particles.step_start, thickness_, kOverlapSlop);
      }
    }
  }
  double max_change = 0.0;
  if (particle_contacts) {
    max_change = std::max(max_change, particle_contacts_.project(particles, substep_, step_,
                                                                 friction_, kinematic_reaction_));
  }
  if (self_collision) {
    max_change =
        std::max(max_change, self_collision_pairs_.project(particles, thickness_, substep_,
                                                           friction_, kinematic_reaction_));
  }
  max_change = std::max(max_change, projectObstaclesAndBounds(particles, first_pass));
  return max_change;
}

void Collisions::preStabilizeObstacles(Particles& p, double max_shift) {
  const std::size_t count = shapes_.size();
  for (std::size_t k = 0; k < count; ++k) {
    worldBounds(shapes_[k], frame_end_[k], obstacle_lo_[k], obstacle_hi_[k]);
  }
  // Last step's allowances back to zero: only the particles that had one have any to clear, so
  // a step does not write every particle's slot of every obstacle.
  for (int i = 0; i < p.size(); ++i) {
    if (!has_allowance_[i]) continue;
    for (std::size_t k = 0; k < count; ++k) obstacle_allowance_[slotOf(i, k)] = 0.0;
    has_allowance_[i] = 0;
  }
  if (count == 0) return;
  // Blocks of kCullBlock particles culled as in the first pass (projectBlockFirstPass): an
  // obstacle apart from the box of the block's spheres is apart from each sphere (the same
  // arithmetic as outsideBounds), so each particle meets only its block's list `near`, in
  // order, until a shift moves it: from there on every later obstacle, as a loop over all of
  // them would. The same shifts and allowances as testing every pair, at a cost that grows with
  // the particles near each obstacle, not with particles times obstacles.
  int* near = near_obstacles_.data();
  for (int block = 0; block < p.size(); block += kCullBlock) {
    const int block_end = std::min(p.size(), block + kCullBlock);
    // The spheres' boxes x -/+ r: path boxes from x to x (computePathBoxes); `every` when one
    // has a coordinate not a number.
    PathBox box[kCullBlock];
    Eigen::Array3d lo, hi;
    const bool every =
        computePathBoxes(path_box_kernel_, p, p.position, block, block_end, box, lo, hi);
    const int near_count = listNearObstacles(lo, hi, every, near);
    if (near_count == 0) continue;
    for (int i = block; i < block_end; ++i) {
      if (p.inverse_mass[i] == 0.0) continue;
      int q = 0;
      bool every_later = false;
      for (std::size_t k = static_cast<std::size_t>(near[0]); k < count;
           k = every_later        ? k + 1
               : ++q < near_count ? static_cast<std::size_t>(near[q])
                                  : count) {
        if (!enabled_[k]) continue;
        // Outside the shape's bounds grown by the radius: no overlap to separate (and no query,
        // which for a mesh is a tree search); its allowance stays zero.
        if (outsideBounds(p.position[i], p.radius[i], obstacle_lo_[k], obstacle_hi_[k])) continue;
        // Nor outside its bounding ball grown by the radius, with a margin far above rounding:
        // the clearance below would be positive (the slot's allowance is already zero).
        if (ball_cull_[k] && outsideBoundingBall(p.position[i], p.radius[i], static_cast<int>(k))) {
          continue;
        }
        Vec3 normal;
        const double clearance =
            signedDistance(shapes_[k], frame_end_[k].toLocal(p.position[i]), normal) - p.radius[i];
        double left = 0.0;
        if (clearance < -kOverlapSlop * p.radius[i]) {
          const double shift = std::min(-clearance, max_shift);
          p.position[i] += shift * (frame_end_[k].rotation * normal);
          left = -clearance - shift;
          every_later = true;
        }
        const double allowance = allowanceFor(left, p.radius[i], kOverlapSlop);
        obstacle_allowance_[slotOf(i, k)] = allowance;
        if (allowance > 0.0) has_allowance_[i] = 1;
      }
    }
  }
}

// Obstacles, then the bounds. Each touches only the particle it projects (and the obstacles its
// own contact slots), so with threads (solver.threads) each takes a consecutive range of
// particles: the same result for every count.
double Collisions::projectObstaclesAndBounds(Particles& p, bool first_pass) {
  if (shapes_.empty() && !bounds_.enabled) return 0.0;
  const int threads =
      pool_ != nullptr && p.size() >= 2 * kParticlesPerThread ? pool_->threads() : 1;
  const int count = static_cast<int>(shapes_.size());
  // A single obstacle's own cull costs a particle what its share of a block's box would (and a
  // cloth lying on its only obstacle, a towel on a table, would pay for both).
  const bool by_blocks = first_pass && count > 1;
  auto range = [&](int begin, int end, int t) {
    int* near = near_obstacles_.data() + static_cast<std::size_t>(t) * count;
    double max_change = 0.0;
    for (int block = begin; block < end; block += kCullBlock) {
      const int block_end = std::min(end, block + kCullBlock);
      if (by_blocks) {
        max_change = std::max(max_change, projectBlockFirstPass(p, block, block_end, near));
        continue;
      }
      // Every obstacle, each culled for the particle alone (nullptr): after the first pass a
      // particle pushed earlier in the substep has a contact to keep whatever its path.
      for (int i = block; i < block_end; ++i) {
        if (p.inverse_mass[i] == 0.0) continue;  // kinematic: prescribed, left alone
        max_change =
            std::max(max_change, projectObstaclesOn<false>(p, i, first_pass, nullptr, count));
        max_change = std::max(max_change, projectBoundsOn(p.position[i]));
      }
    }
    return max_change;
  };
  if (threads == 1) return range(0, p.size(), 0);
  double* max_change = thread_max_change_;
  pool_->runRanges(p.size(),
                   [&](int begin, int end, int t) { max_change[t] = range(begin, end, t); });
  return *std::max_element(max_change, max_change + threads);
}

// The enabled obstacles whose bounds the box [lo, hi] reaches, in increasing order, into `near`;
// every enabled obstacle when the box is not one (`every`: a coordinate not a number). Returns
// how many. Both culls by blocks use it: the pre-stabilization with the block's spheres, the
// first pass with its paths.
int Collisions::listNearObstacles(const Eigen::Array3d& lo, const Eigen::Array3d& hi, bool every,
                                  int* near) const {
  int near_count = 0;
  const int count = static_cast<int>(shapes_.size());
  for (int k = 0; k < count; ++k) {
    if (enabled_[k] && (every || !boxesApart(lo, hi, obstacle_lo_[k], obstacle_hi_[k]))) {
      near[near_count++] = k;
    }
  }
  return near_count;
}

// The first pass over the free particles [begin, end): each one's path box once (the block's in
// one loop, computePathBoxes, in SIMD registers where the processor has them), for three culls
// in turn, each exact, so that a particle that can touch nothing costs that box and a few
// comparisons (a cloth falling or lying clear of most obstacles: most of its particles):
//  - the block: an obstacle apart from the box holding all of the block's boxes is apart from
//    each (its list `near`, in increasing order);
//  - the particle: of those, the obstacles its own box reaches; none, and projectObstaclesOn
//    would skip each of them unread, so it is not called;
//  - the bounds: a particle no contact moved lies inside its box, so a box inside the bounds
//    leaves it unclamped (projectBoundsOn would change nothing).
// A box that is not one (a coordinate not a number) lists every enabled obstacle and is never
// inside the bounds, so that particle goes through every test as before.
double Collisions::projectBlockFirstPass(Particles& p, int begin, int end, int* near) {
  PathBox box[kCullBlock];  // each free particle's path box
  Eigen::Array3d lo, hi;
  const bool every = computePathBoxes(path_box_kernel_, p, begin, end, box, lo, hi);
  const int near_count = listNearObstacles(lo, hi, every, near);
  const bool bounds_apply = bounds_.enabled;
  // The whole block clear of every obstacle and inside the bounds: nothing to do. (Not with a
  // box that is not one: the union's min and max may have dropped its NaN.)
  if (near_count == 0 && !every &&
      (!bounds_apply || ((lo >= bounds_.min.array()).all() && (hi <= bounds_.max.array()).all()))) {
    return 0.0;
  }
  // Each particle's box against the listed obstacles' bounds and the scene's, in one loop over
  // the block (reachedObstacles): a bit for each listed obstacle it reaches, and whether it lies
  // inside the bounds.
  PathBox* near_box = near_boxes_.data() + (near - near_obstacles_.data());
  for (int q = 0; q < near_count; ++q) {
    near_box[q] = boxOfBounds(obstacle_lo_[near[q]], obstacle_hi_[near[q]]);
  }
  const PathBox bounds = boxOfBounds(bounds_.min, bounds_.max);
  std::uint64_t reach[kCullBlock];
  unsigned char inside[kCullBlock];
  reachedObstacles(path_box_kernel_, p, begin, end, box, near_box, near_count, bounds, reach,
                   inside);
  double max_change = 0.0;
  for (int i = begin; i < end; ++i) {
    if (p.inverse_mass[i] == 0.0) continue;  // kinematic: prescribed, left alone
    // The first listed obstacle its box reaches, of those it may touch (the bits in increasing
    // order; past the bits' reach, box by box).
    int first = near_count;
    for (std::uint64_t bits = reach[i - begin]; bits != 0; bits &= bits - 1) {
      const int q = __builtin_ctzll(bits);
      if (!clearOfStillShape(near[q], p.position[i], p.substep_start[i], p.radius[i])) {
        first = q;
        break;
      }
    }
    for (int q = kMostReachTests; first == near_count && q < near_count; ++q) {
      if (!boxesApart(box[i - begin].low(), box[i - begin].high(), obstacle_lo_[near[q]],
                      obstacle_hi_[near[q]]) &&
          !clearOfStillShape(near[q], p.position[i], p.substep_start[i], p.radius[i])) {
        first = q;
      }
    }
    if (first < near_count) {
      max_change = std::max(max_change,
                            projectObstaclesOn<true>(p, i, true, near + first, near_count - first));
    } else if (bounds_apply && inside[i - begin]) {
      continue;
    }
    if (bounds_apply) max_change = std::max(max_change, projectBoundsOn(p.position[i]));
  }
  return max_change;
}

// A shape that stays put over the substep: in its frame the path is as long as in the world's,
// and the distance is at least |x - centre| less the bounding radius (boundingRadius). A
// particle clear of that ball by more than its path, with a margin far above rounding, is one
// projectObstaclesOn's exact test (distance - r >= path length) skips too: found with neither
// frame's product, a square root of theirs or a normal.
bool Collisions::clearOfStillShape(int k, const Vec3& x, const Vec3& start, double r) const {
  if (!still_[k]) return false;
  const double px = x.x() - start.x(), py = x.y() - start.y(), pz = x.z() - start.z();
  return outsideBoundingBall(x, r + std::sqrt(px * px + py * py + pz * pz), k);
}

// True when x lies farther than reach from obstacle k's bounding ball at the substep's end, by a
// relative 1e-9 of the squares (rounding in the distance and in the frame's product is a few
// units in the last place). A coordinate at a time: x has often just been stored so.
bool Collisions::outsideBoundingBall(const Vec3& x, double reach, int k) const {
  const Vec3& centre = frame_end_[k].translation;
  const double cx = x.x() - centre.x(), cy = x.y() - centre.y(), cz = x.z() - centre.z();
  const double far = bound_radius_[k] + reach;
  return cx * cx + cy * cy + cz * cz > (1.0 + 1e-9) * far * far;
}

// Particle-environment contact (seed eq. plane_constraint, extended to any shape through its
// signed distance): C = distance(x) - r >= 0, the full correction to the particle since the shape
// is immovable, along the surface normal. Swept in the shape's frame for no tunnelling (see
// collisions.h), followed by friction relative to the shape's own motion over the substep.
template <bool kFirstReaches>
double Collisions::projectObstaclesOn(Particles& p, int i, bool first_pass, const int* near,
                                      int near_count) {
  const std::size_t count = shapes_.size();
  double max_change = 0.0;
  Vec3& x = p.position[i];
  const Vec3& start = p.substep_start[i];
  const double r = p.radius[i];
  // The obstacles of `near` in order until a contact moves the particle: its path may then reach
  // bounds that its block's paths kept out of, so from there on every later obstacle.
  int q = 0;
  bool every_later = near == nullptr;
  auto next = [&](std::size_t k) {
    if (every_later) return k + 1;
    return ++q < near_count ? static_cast<std::size_t>(near[q]) : count;
  };
  const std::size_t first = every_later      ? 0
                            : near_count > 0 ? static_cast<std::size_t>(near[0])
                                             : count;
  for (std::size_t k = first; k < count; k = next(k)) {
    if (!enabled_[k]) continue;
    const std::size_t slot = slotOf(i, k);
    // Cheap cull: a particle whose path of this substep (the segment from its start, in the box
    // of its ends grown by its radius) stays out of the obstacle's bounds cannot touch it, unless
    // it was pushed out earlier in this substep (never so in its first pass).
    bool apart = false;
    if (!(kFirstReaches && k == first)) {
      Eigen::Array3d path_lo, path_hi;
      pathBox(x, start, r, path_lo, path_hi);
      apart = boxesApart(path_lo, path_hi, obstacle_lo_[k], obstacle_hi_[k]);
    }
    if (apart && first_pass) continue;  // (the contact's state not even read)
    ContactState& state = obstacle_contacts_[slot];
    const bool pushed = state.substep == substep_ && state.depth > 0.0;
    if (apart && !pushed) continue;
    const Shape& shape = shapes_[k];
    const Frame& begin = frame_begin_[k];
    const Frame& end = frame_end_[k];
    // (The caller of a kFirstReaches pass has tested the first obstacle so already.)
    if (!pushed && !(kFirstReaches && k == first) &&
        clearOfStillShape(static_cast<int>(k), x, start, r)) {
      continue;
    }
    const Vec3 b = end.toLocal(x);        // where the particle is, relative to the shape now
    const Vec3 a = begin.toLocal(start);  // ... and where it was
    const bool mesh = shape.type == ShapeType::kMesh;
    // |b - a| as Eigen's norm sums it, ((dx^2 + dy^2) + dz^2), but from the coordinates as they
    // come: b and a are stored a coordinate at a time, and a 16-byte reload of them waits.
    const double dx = b.x() - a.x(), dy = b.y() - a.y(), dz = b.z() - a.z();
    const double path_length = std::sqrt((dx * dx + dy * dy) + dz * dz);
    if (mesh && !pushed) {
      // A mesh query costs a tree search; the last one bounds this one for free. The distance
      // is 1-Lipschitz, so d(b) >= d(b_last) - |b - b_last| (local frame): when even that
      // bound clears the segment, the test below would skip it too.
      const double lower = mesh_distance_[slot] - (b - mesh_point_[slot]).norm() - r;
      if (lower >= path_length) continue;
    } else if (!pushed && surelyFartherThan(shape, b, r + path_length)) {
      continue;  // the test below would skip it too, after a square root and a normal
    }
    Vec3 normal_b;
    int* hint = &mesh_hint_[slot];
    const double clearance = signedDistance(shape, b, normal_b, hint) - r;
    if (mesh) {
      mesh_distance_[slot] = clearance + r;
      mesh_point_[slot] = b;
    }
    // The distance is 1-Lipschitz: a segment whose end is farther from the surface than its
    // length never touched the shape (unless it was pushed out earlier in this substep).
    if (clearance >= path_length && !pushed) continue;
    Vec3 normal_a;
    const double start_distance = signedDistance(shape, a, normal_a, hint);
    // The window's base is the particle's place on the shape when it began: carried by the
    // shape, it is the point under the particle that friction holds it to.
    if (state.beginSubstep(substep_, step_, start_distance < (1.0 + kTouchGap) * r, true)) {
      state.base = a;
    }
    const double allowance = obstacle_allowance_[slot];
    double c = clearance;
    Vec3 normal = normal_b;
    double t = 0.0;
    Vec3 normal_entry;
    if (allowance > 0.0) {
      c = clearance + allowance;  // started inside: only not deeper
    } else if (sweepSphere(shape, a, b, r, start_distance, normal_a, t, normal_entry, hint)) {
      if (!(clearance < 0.0 && normal_b.dot(normal_entry) > 0.0)) {
        // Crossed or cut through: back onto the tangent plane where the sphere entered.
        c = (b - (a + t * (b - a))).dot(normal_entry);
        normal = normal_entry;
      }
    }
    if (c < 0.0 || state.depth > 0.0) {
      const Vec3 n = end.rotation * normal;
      const double push = contactIncrement(c, state);
      x += push * n;
      every_later = true;
      state.normal = n;
      max_change = std::max(max_change, std::abs(push));
    }
    if (state.frictionDepth() > 0.0) {
      // The shape carries the point under the particle along with it: the relative
      // displacement is measured from there, so a moving shape drags what rests on it.
      x += frictionCorrection(x - end.toWorld(state.base), state, obstacle_friction_[k]);
      every_later = true;
    }
  }
  return max_change;
}

// The seed's box (C1): x_i = min(max(x_i, min), max), component-wise.
double Collisions::projectBoundsOn(Vec3& x) const {
  if (!bounds_.enabled) return 0.0;
  if ((x.array() >= bounds_.min.array()).all() && (x.array() <= bounds_.max.array()).all()) {
    return 0.0;  // inside (the usual case): no clamp, no square root
  }
  const Vec3 clamped = x.cwiseMax(bounds_.min).cwiseMin(bounds_.max);
  const double moved = (clamped - x).norm();
  x = clamped;
  return moved;
}

void Collisions::getColliderState(int collider, BodySnapshot& body) const {
  body.pose = obstacles_[collider].pose;
  body.target = obstacle_targets_[collider];
  body.enabled = enabled_[collider] != 0;
  body.jump_to_target = teleport_[collider] != 0;
}

void Collisions::setColliderState(int collider, const BodySnapshot& body) {
  ++collider_changes_;
  obstacles_[collider].pose = body.pose;
  obstacle_targets_[collider] = body.target;
  enabled_[collider] = body.enabled ? 1 : 0;
  teleport_[collider] = body.jump_to_target ? 1 : 0;
}

void Collisions::getMeshContacts(std::vector<MeshContactCache>& caches) const {
  caches.clear();
  const std::size_t count = obstacles_.size();
  const double never = -std::numeric_limits<double>::infinity();
  // Particle by particle, each one's colliders in order (the slots lie obstacle by obstacle).
  for (int i = 0; i < slot_particles_; ++i) {
    for (std::size_t k = 0; k < count; ++k) {
      const std::size_t slot = slotOf(i, k);
      if (mesh_hint_[slot] == -1 && mesh_distance_[slot] == never) continue;  // never queried
      MeshContactCache cache;
      cache.particle = i;
      cache.collider = static_cast<int>(k);
      cache.triangle = mesh_hint_[slot];
      cache.distance = mesh_distance_[slot];
      cache.point = mesh_point_[slot];
      caches.push_back(cache);
    }
  }
}

void Collisions::setMeshContacts(const std::vector<MeshContactCache>& caches) {
  std::fill(mesh_hint_.begin(), mesh_hint_.end(), -1);
  std::fill(mesh_distance_.begin(), mesh_distance_.end(), -std::numeric_limits<double>::infinity());
  std::fill(mesh_point_.begin(), mesh_point_.end(), Vec3::Zero());
  for (const MeshContactCache& cache : caches) {
    const std::size_t slot = slotOf(cache.particle, static_cast<std::size_t>(cache.collider));
    mesh_hint_[slot] = cache.triangle;
    mesh_distance_[slot] = cache.distance;
    mesh_point_[slot] = cache.point;
  }
}

void Collisions::findCandidatesNow(const Particles& particles, const ClothTopology& topology) {
  checked_substep_ = -1;
  computeSweptBoxes(particles, 0.0, 0.0, 0.0);
  findCandidates(particles, topology, true, true);
}

void Collisions::setSearchWindow(int window, int substeps) {
  window_setting_ = window;
  substeps_ = std::max(1, substeps);
}

void Collisions::endStep() {
  // The adaptive window ("The search window", collisions.h): far candidates worked on against the
  // particles each search passes over.
  const double far_work = static_cast<double>(self_collision_pairs_.takeFarPairSubsteps());
  if (window_setting_ == 0 && searches_in_step_ > 0) {
    const double per_search = static_cast<double>(std::max<std::size_t>(1, box_lo_.size())) *
                              static_cast<double>(searches_in_step_);
    adaptive_window_ = window_substeps_;
    if (far_work > kWindowHalves * per_search) {
      adaptive_window_ = std::max(1, window_substeps_ / 2);
    } else if (far_work < kWindowDoubles * per_search) {
      adaptive_window_ = std::min(substeps_, 2 * window_substeps_);
    }
  }
  for (std::size_t k = 0; k < obstacles_.size(); ++k) obstacles_[k].pose = obstacle_targets_[k];
}

void Collisions::rememberStepStart() {
  start_pose_.resize(obstacles_.size());
  for (std::size_t k = 0; k < obstacles_.size(); ++k) start_pose_[k] = obstacles_[k].pose;
  start_step_ = step_;
  start_window_ = adaptive_window_;
}

void Collisions::restoreStepStart() {
  for (std::size_t k = 0; k < obstacles_.size(); ++k) obstacles_[k].pose = start_pose_[k];
  step_ = start_step_;
  adaptive_window_ = start_window_;
}

std::size_t Collisions::releaseExcessCapacity() {
  return particle_contacts_.releaseExcessCapacity() + self_collision_pairs_.releaseExcessCapacity();
}

void Collisions::countInside(const Particles& particles, double slack, std::vector<int>& inside,
                             std::vector<int>& first_inside) const {
  inside.assign(shapes_.size(), 0);
  first_inside.assign(shapes_.size(), -1);
  for (std::size_t k = 0; k < shapes_.size(); ++k) {
    if (!enabled_[k]) continue;
    const Frame frame = frameFromPose(obstacles_[k].pose);
    for (int i = 0; i < particles.size(); ++i) {
      if (particles.inverse_mass[i] == 0.0) continue;
      const double depth =
          particles.radius[i] - signedDistance(shapes_[k], frame.toLocal(particles.position[i]));
      if (depth <= slack) continue;
      if (inside[k]++ == 0) first_inside[k] = i;
    }
  }
}

double Collisions::maxPenetration(const Particles& particles, const ClothTopology& topology) const {
  double depth = 0.0;
  if (bounds_.enabled) {
    for (int i = 0; i < particles.size(); ++i) {
      const Vec3& x = particles.position[i];
      depth = std::max(depth, (bounds_.min - x).maxCoeff());
      depth = std::max(depth, (x - bounds_.max).maxCoeff());
    }
  }
  for (std::size_t k = 0; k < shapes_.size(); ++k) {
    if (!enabled_[k]) continue;
    const Frame frame = frameFromPose(obstacles_[k].pose);
    Vec3 lo, hi;
    worldBounds(shapes_[k], frame, lo, hi);
    for (int i = 0; i < particles.size(); ++i) {
      if (particles.inverse_mass[i] == 0.0) continue;  // prescribed: not the solver's to fix
      if (outsideBounds(particles.position[i], particles.radius[i], lo, hi)) continue;
      depth = std::max(depth, particles.radius[i] -
                                  signedDistance(shapes_[k], frame.toLocal(particles.position[i])));
    }
  }
  if (particleContactsActive(particles)) {
    depth = std::max(depth, particle_contacts_.maxPenetration(particles));
  }
  if (selfCollisionActive(topology)) {
    depth = std::max(depth, self_collision_pairs_.maxPenetration(particles, thickness_));
  }
  return depth;
}

}  // namespace pbd_cloth
