// What every contact kind (particle-shape, particle-particle, vertex-triangle) keeps while a substep
// runs, and the position-level friction of the collision seed that all three share.
#pragma once

#include <algorithm>

#include "pbd_cloth/particles.h"
#include "pbd_cloth/scene_config.h"

namespace pbd_cloth {

// Per-contact state, valid for one substep (a state stamped with an older substep is empty).
// Accumulating over the passes of a substep makes the friction law independent of the pass count:
// one pass gives exactly the seed's formula, more passes give the same total instead of applying
// the kinetic limit once per pass.
struct ContactState {
  int substep = -1;
  double depth = 0.0;            // normal correction resolved this substep: the seed's d
  Vec3 normal = Vec3::UnitZ();   // contact normal of the last correction
  Vec3 friction = Vec3::Zero();  // relative friction correction applied this substep

  bool current(int stamp) const { return substep == stamp; }
  void begin(int stamp) {
    substep = stamp;
    depth = 0.0;
    friction.setZero();
  }
};

// Penetration a contact may keep during a step: the overlap left at the step start after
// pre-stabilisation, when deeper than the slop (a fraction of the contact distance). Such an
// overlap is only kept from growing and is removed by pre-stabilisation at the next step start,
// without velocity (Macklin et al. 2014, sec. 4.4), instead of by the projection, whose correction
// would become velocity ("explosive popping"). Zero for every contact that is not initially deep.
inline double allowanceFor(double overlap, double contact_distance, double slop) {
  return overlap > slop * contact_distance ? overlap : 0.0;
}

// Position-level Coulomb friction (collision seed, eq. friction_correction; Bender, Mueller, Macklin
// 2017, eqs. 27-28). `relative` is the relative displacement of the two sides over the substep,
// Delta p_rel = (p*_i - p_i) - (p*_j - p_j); `depth` the penetration d resolved in the substep.
// Returns the increment of relative correction to apply now (distribute it by inverse mass):
// the total correction is -Delta p_t when |Delta p_t| <= mu_s d (static: the tangential motion is
// cancelled) and -Delta p_t min(mu_k d / |Delta p_t|, 1) otherwise (kinetic), where Delta p_t is
// the tangential displacement the contact would have had without friction in this substep.
inline Vec3 frictionCorrection(const Vec3& relative, ContactState& state,
                               const FrictionConfig& friction) {
  const Vec3& n = state.normal;
  const Vec3 tangential = relative - relative.dot(n) * n;
  const Vec3 applied = state.friction - state.friction.dot(n) * n;
  const Vec3 free = tangential - applied;  // Delta p_t of the seed
  const double length = free.norm();
  Vec3 total;
  if (length <= friction.static_coefficient * state.depth) {
    total = -free;
  } else {
    total = -std::min(friction.kinetic_coefficient * state.depth / length, 1.0) * free;
  }
  const Vec3 increment = total - applied;
  state.friction = total;
  return increment;
}

}  // namespace pbd_cloth
