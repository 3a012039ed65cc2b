// Particle-particle contact of the collision seed, C(p_i, p_j) = |p_i - p_j| - (r_i + r_j) >= 0
// (eq. particle_particle_constraint), for granular particles among themselves and against cloth
// particles. Cloth-cloth contact is the vertex-triangle self-collision's job (self_collision.h).
#pragma once

#include <vector>

#include "pbd_cloth/collision/contact.h"
#include "pbd_cloth/geometry/spatial_hash.h"
#include "pbd_cloth/model/particles.h"

namespace pbd_cloth {

struct ParticlePair {
  int i = 0;               // always a granular particle
  int j = 0;               // granular (j > i) or cloth
  double allowance = 0.0;  // overlap tolerated this step (allowanceFor)
  ContactState state;
};

class ParticleContacts {
 public:
  void reserve(const Particles& particles);

  // Broad phase, once per step: every pair whose swept boxes [lo, hi] (the motion bound of the
  // step), grown by the radii, overlap. All particles are hashed (cell: the mean box) and each
  // granular particle queries its box. `keep_states` (a search again within the step): a pair
  // that was listed before keeps its contact state (friction window, its base and depth).
  void findPairs(const Particles& particles, const Vec3Array& lo, const Vec3Array& hi,
                 bool keep_states = false);

  // Pre-stabilisation (Macklin et al. 2014, sec. 4.4): one pass that pushes pairs overlapping by
  // more than the slop (a fraction of r_i + r_j) apart by at most max_shift each, on the positions
  // before the step's first prediction, so the separation becomes no velocity. Shallower overlaps
  // (the residual of a loaded stack) are left to the projection, whose friction holds them: a
  // frictionless push every step would make a pile creep.
  void preStabilize(Particles& particles, double max_shift, double slop) const;
  // After pre-stabilisation: the overlap each pair may keep this step (allowanceFor, `slop` a
  // fraction of r_i + r_j), measured in `positions` (those of the step start).
  void measureAllowances(const Particles& particles, const Vec3Array& positions, double slop);

  // One projection pass over the candidate pairs, each followed by its friction (window of the
  // step, see ContactState); returns the largest correction. `substep` and `step` are stamps.
  // A kinematic particle of a pair gets the pair's multiplier times its gradient added to
  // `reaction` (Collisions::kinematicReaction).
  double project(Particles& particles, int substep, int step, const Friction& friction,
                 Vec3Array& reaction);

  // Deepest overlap (r_i + r_j - |p_i - p_j|) over the candidate pairs (m).
  double maxPenetration(const Particles& particles) const;
  int pairCount() const { return static_cast<int>(pairs_.size()); }
  // Between steps: the pair lists go back to their reserve after a step that outgrew it
  // (SelfCollision::releaseExcessCapacity). Returns the bytes released.
  std::size_t releaseExcessCapacity();

 private:
  void findNewPairs(const Particles& particles, const Vec3Array& lo, const Vec3Array& hi);
  void carryStates();

  SpatialHash hash_;
  Vec3Array grown_lo_;  // swept boxes grown by the particle radius
  Vec3Array grown_hi_;
  std::size_t reserved_pairs_ = 0;  // capacity reserve() gave pairs_ and previous_
  std::vector<ParticlePair> pairs_;
  std::vector<ParticlePair> previous_;  // the list before a search within the step
};

}  // namespace pbd_cloth
