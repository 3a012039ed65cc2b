#include "pbd_cloth/sim/sleeping.h"

#include <algorithm>

namespace pbd_cloth {

void Sleeping::build(const Particles& particles) {
  still_from_ = particles.position;
  still_begun_ = false;
  still_time_ = 0.0;
}

void Sleeping::wake() {
  asleep_ = false;
  still_begun_ = false;
  still_time_ = 0.0;
}

bool Sleeping::canSleepThrough(const Particles& particles, const Collisions& collisions) const {
  if (!asleep_) return false;
  for (int i = 0; i < particles.size(); ++i) {
    if (particles.isKinematic(i) && particles.kinematic_to[i] != particles.position[i]) {
      return false;
    }
  }
  if (collisions.colliderChanges() != sleep_collider_changes_) return false;
  return !collisions.colliderMovesNear(sleep_lo_, sleep_hi_, sleep_margin_);
}

void Sleeping::update(const SolverConfig& solver, Particles& particles,
                      const Collisions& collisions, double dt) {
  const double limit = solver.sleep_speed;
  if (limit <= 0.0) return;
  // Where the stillness began: each particle's position then. still_from_ has the particles'
  // count from build(), so the assignment copies without allocating (a count changed since, by
  // a state set from outside, sizes it again).
  auto beginStillness = [this, &particles] {
    still_from_ = particles.position;
    still_begun_ = true;
    still_time_ = 0.0;
  };
  if (!still_begun_ || still_from_.size() != particles.position.size()) {
    beginStillness();
    return;
  }
  const double still_reach = limit * solver.sleep_time;
  double farthest_sq = 0.0;
  for (int i = 0; i < particles.size(); ++i) {
    if (!particles.isKinematic(i)) {
      farthest_sq = std::max(farthest_sq, (particles.position[i] - still_from_[i]).squaredNorm());
    }
  }
  if (!(farthest_sq <= still_reach * still_reach)) {  // (a NaN is not still either)
    beginStillness();
    return;
  }
  still_time_ += dt;
  if (still_time_ + 1e-12 < solver.sleep_time || particles.size() == 0) return;
  asleep_ = true;
  sleep_lo_ = sleep_hi_ = particles.position[0];
  double reach = 0.0;
  for (int i = 0; i < particles.size(); ++i) {
    if (!particles.isKinematic(i)) particles.velocity[i].setZero();
    sleep_lo_ = sleep_lo_.cwiseMin(particles.position[i]);
    sleep_hi_ = sleep_hi_.cwiseMax(particles.position[i]);
    reach = std::max(reach, particles.radius[i]);
  }
  // Within twice the largest contact reach of the particles, a moving collider may touch them.
  sleep_margin_ = 2.0 * reach + 0.01;
  sleep_collider_changes_ = collisions.colliderChanges();
}

}  // namespace pbd_cloth
