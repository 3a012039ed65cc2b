// Particle-particle contact of the collision seed, C(p_i, p_j) = |p_i - p_j| - (r_i + r_j) >= 0
// (eq. particle_particle_constraint), for granular particles among themselves and against cloth
// particles. Cloth-cloth contact is the vertex-triangle self-collision's job (self_collision.h).
#pragma once

#include <vector>

#include "pbd_cloth/contact.h"
#include "pbd_cloth/particles.h"
#include "pbd_cloth/spatial_hash.h"

namespace pbd_cloth {

struct ParticlePair {
  int i = 0;  // always a granular particle
  int j = 0;  // granular (j > i) or cloth
  double allowance = 0.0;  // overlap tolerated this step (allowanceFor)
  ContactState state;
};

class ParticleContacts {
 public:
  void reserve(const Particles& particles);

  // Broad phase, once per step: every pair whose swept boxes [lo, hi] (the motion bound of the
  // step), grown by the radii, overlap. Hashes the box corners with a cell no smaller than any box,
  // so a query of the neighbouring cells finds them all.
  void findPairs(const Particles& particles, const Vec3Array& lo, const Vec3Array& hi);

  // Pre-stabilisation (Macklin et al. 2014, sec. 4.4): one pass that pushes overlapping pairs apart
  // by at most max_shift each, on the positions before the step's first prediction, so the
  // separation becomes no velocity.
  void preStabilize(Particles& particles, double max_shift) const;
  // After pre-stabilisation: the overlap each pair may keep this step (allowanceFor, `slop` a
  // fraction of r_i + r_j), measured in `positions` (those of the step start).
  void measureAllowances(const Particles& particles, const Vec3Array& positions, double slop);

  // One projection pass over the candidate pairs, then friction; returns the largest correction.
  double project(Particles& particles, int substep, const FrictionConfig& friction);

  // Deepest overlap (r_i + r_j - |p_i - p_j|) over the candidate pairs (m).
  double maxPenetration(const Particles& particles) const;
  int pairCount() const { return static_cast<int>(pairs_.size()); }

 private:
  SpatialHash hash_;
  Vec3Array grown_lo_;  // swept boxes grown by the particle radius
  Vec3Array grown_hi_;
  std::vector<ParticlePair> pairs_;
};

}  // namespace pbd_cloth
