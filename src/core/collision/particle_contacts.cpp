#include "pbd_cloth/collision/particle_contacts.h"

#include "pbd_cloth/collision/buffer_capacity.h"

#include <algorithm>
#include <cmath>

namespace pbd_cloth {

namespace {

// Below this centre distance two particles have no direction between them (coincident).
constexpr double kMinDistance = 1e-12;

// Unit vector from j to i; coincident particles fall back on where they were at the substep start,
// then on +z, so the pair still separates instead of dividing by zero.
Vec3 separationDirection(const Particles& p, int i, int j, const Vec3& delta, double distance) {
  if (distance > kMinDistance) return delta / distance;
  const Vec3 before = p.substep_start[i] - p.substep_start[j];
  const double length = before.norm();
  return length > kMinDistance ? Vec3(before / length) : Vec3::UnitZ();
}

// A pair's multiplier (vector) `lambda` moves i by w_i lambda and j by -w_j lambda; a kinematic end
// stays, and lambda (i) or -lambda (j) is its reaction.
void addReaction(const Particles& p, int i, int j, const Vec3& lambda, Vec3Array& reaction) {
  if (p.inverse_mass[i] == 0.0) reaction[i] += lambda;
  if (p.inverse_mass[j] == 0.0) reaction[j] -= lambda;
}

}  // namespace

void ParticleContacts::reserve(const Particles& particles) {
  const int n = particles.size();
  hash_.reserve(n);
  grown_lo_.reserve(n);
  grown_hi_.reserve(n);
  const int granular = n - particles.cloth_count;
  reserved_pairs_ = 16 * static_cast<std::size_t>(granular);
  pairs_.reserve(reserved_pairs_);
  previous_.reserve(reserved_pairs_);
}

std::size_t ParticleContacts::releaseExcessCapacity() {
  return shrinkToReserve(pairs_, reserved_pairs_) + shrinkToReserve(previous_, reserved_pairs_);
}

void ParticleContacts::findPairs(const Particles& p, const Vec3Array& lo, const Vec3Array& hi,
                                 bool keep_states) {
  // The old list is kept aside (a swap: no copy, no allocation) to hand its states on.
  if (keep_states) pairs_.swap(previous_);
  pairs_.clear();
  findNewPairs(p, lo, hi);
  if (keep_states) carryStates();
}

// A contact found again keeps what it has measured so far in this step: without it, a search
// within the step (a particle left its swept box) would reopen every friction window at that
// substep, forgetting the slip still to be caught up and the depth resolved, and a resting pile
// would creep by as much each time. Both lists are ordered by i (the query loop): the old pairs
// of each new pair's i are a short range found by bisection.
void ParticleContacts::carryStates() {
  const auto by_first = [](const ParticlePair& pair, int i) { return pair.i < i; };
  for (ParticlePair& pair : pairs_) {
    auto old = std::lower_bound(previous_.begin(), previous_.end(), pair.i, by_first);
    for (; old != previous_.end() && old->i == pair.i; ++old) {
      if (old->j == pair.j) {
        pair.state = old->state;
        break;
      }
    }
  }
}

void ParticleContacts::findNewPairs(const Particles& p, const Vec3Array& lo, const Vec3Array& hi) {
  const int n = p.size();
  if (n == p.cloth_count) return;  // no granular particles
  grown_lo_.resize(n);
  grown_hi_.resize(n);
  // The cell: the mean box extent (the boxes of fast particles are filed in several cells).
  double cell = 0.0;
  for (int k = 0; k < n; ++k) {
    grown_lo_[k] = lo[k].array() - p.radius[k];
    grown_hi_[k] = hi[k].array() + p.radius[k];
    cell += (grown_hi_[k] - grown_lo_[k]).maxCoeff() / n;
  }
  if (!(cell > 0.0) || !std::isfinite(cell)) return;
  hash_.build(grown_lo_, grown_hi_, n, cell);
  for (int i = p.cloth_count; i < n; ++i) {
    hash_.forEachOverlapping(grown_lo_[i], grown_hi_[i], [&](int j) {
      if (j == i || (j >= p.cloth_count && j < i)) return;  // each granular pair once
      if (p.inverse_mass[i] == 0.0 && p.inverse_mass[j] == 0.0) return;
      ParticlePair pair;
      pair.i = i;
      pair.j = j;
      pairs_.push_back(pair);
    });
  }
}

void ParticleContacts::preStabilize(Particles& p, double max_shift, double slop) const {
  for (const ParticlePair& pair : pairs_) {
    const double wi = p.inverse_mass[pair.i], wj = p.inverse_mass[pair.j];
    const double w = wi + wj;
    if (w == 0.0) continue;
    const Vec3 delta = p.position[pair.i] - p.position[pair.j];
    const double distance = delta.norm();
    const double contact_distance = p.radius[pair.i] + p.radius[pair.j];
    const double overlap = contact_distance - distance;
    if (overlap <= slop * contact_distance) continue;
    const Vec3 n = separationDirection(p, pair.i, pair.j, delta, distance);
    const double shift = std::min(overlap, max_shift);
    p.position[pair.i] += (wi / w * shift) * n;
    p.position[pair.j] -= (wj / w * shift) * n;
  }
}

void ParticleContacts::measureAllowances(const Particles& p, const Vec3Array& x, double slop) {
  for (ParticlePair& pair : pairs_) {
    const double contact_distance = p.radius[pair.i] + p.radius[pair.j];
    const double overlap = contact_distance - (x[pair.i] - x[pair.j]).norm();
    pair.allowance = allowanceFor(overlap, contact_distance, slop);
  }
}

double ParticleContacts::project(Particles& p, int substep, int step, const Friction& friction,
                                 Vec3Array& reaction) {
  double max_change = 0.0;
  for (ParticlePair& pair : pairs_) {
    const int i = pair.i, j = pair.j;
    const double wi = p.inverse_mass[i], wj = p.inverse_mass[j];
    const double w = wi + wj;
    if (w == 0.0) continue;
    const double contact_distance = p.radius[i] + p.radius[j];
    ContactState& state = pair.state;
    const Vec3 start = p.substep_start[i] - p.substep_start[j];
    if (state.beginSubstep(substep, step, start.norm() < (1.0 + kTouchGap) * contact_distance,
                           false)) {
      state.base = start;
    }
    const Vec3 delta = p.position[i] - p.position[j];
    const double distance = delta.norm();
    // Seed eq. particle_particle_constraint, solved like a stretch constraint: the correction
    // along the centre line is split by inverse mass, which conserves momentum.
    const double c = distance - (contact_distance - pair.allowance);
    if (c < 0.0 || state.depth > 0.0) {
      const Vec3 n = separationDirection(p, i, j, delta, distance);
      const double push = contactIncrement(c, state);
      p.position[i] += (wi / w * push) * n;
      p.position[j] -= (wj / w * push) * n;
      addReaction(p, i, j, (push / w) * n, reaction);
      state.normal = n;
      max_change = std::max(max_change, std::abs(push) * std::max(wi, wj) / w);
    }
    if (state.frictionDepth() > 0.0) {
      const Vec3 relative = (p.position[i] - p.position[j]) - state.base;
      const Vec3 correction = frictionCorrection(relative, state, friction);
      p.position[i] += (wi / w) * correction;
      p.position[j] -= (wj / w) * correction;
      addReaction(p, i, j, correction / w, reaction);
    }
  }
  return max_change;
}

double ParticleContacts::maxPenetration(const Particles& p) const {
  double depth = 0.0;
  for (const ParticlePair& pair : pairs_) {
    if (p.inverse_mass[pair.i] == 0.0 && p.inverse_mass[pair.j] == 0.0) continue;
    depth = std::max(depth, p.radius[pair.i] + p.radius[pair.j] -
                                (p.position[pair.i] - p.position[pair.j]).norm());
  }
  return depth;
}

}  // namespace pbd_cloth
