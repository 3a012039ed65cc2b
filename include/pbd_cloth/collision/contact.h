// What every contact kind (particle-shape, particle-particle, vertex-triangle) keeps while it acts,
// the projection of its normal constraint, and the position-level friction of the collision seed
// that all three share.
#pragma once

#include <algorithm>

#include "pbd_cloth/model/particles.h"

namespace pbd_cloth {

// Coulomb friction of a contact (cloth.friction, an obstacle's or robot.friction).
struct Friction {
  double static_coefficient = 0.5;   // mu_s
  double kinetic_coefficient = 0.4;  // mu_k, <= mu_s
};

// Per-contact state while the contact acts.
//
// Normal: the correction pushed in the current substep (projected Gauss-Seidel, see
// contactIncrement).
//
// Friction: the seed measures the relative displacement over "the time step" and uses the
// penetration d resolved in it (REFERENCE_CASES.md case 10: "the penetration resolved in the
// step"). The window over which both are accumulated opens at the step start, or at the substep in
// which the contact came into touch, and runs on through the substeps of the step while the contact
// stays in touch (within a small gap, kTouchGap, at each substep start) and, against an
// obstacle, has not slid (beginSubstep). For one contact this is the seed's law substep by substep
// (the same accelerations, the same critical angle, test_friction.cpp). But the slip that one
// Gauss-Seidel pass leaves uncorrected (a floor undoing part of the reaction a particle resting on
// another one received) is caught up by the next substeps instead of being forgotten at every
// substep start: measured per substep, that slip makes a granular pile creep at a rate set by the
// substep count (test_granular.cpp). A contact that begins within the step measures from where it
// was when it began, so motion from before it touched is never cancelled.
struct ContactState {
  int substep = -1;              // substep of the last evaluation
  int window = -1;               // step of the friction window
  double depth = 0.0;            // normal correction pushed in this substep
  double window_depth = 0.0;     // normal correction of the window's earlier substeps
  Vec3 normal = Vec3::UnitZ();   // contact normal of the last correction
  Vec3 friction = Vec3::Zero();  // relative friction correction accumulated over the window
  Vec3 base = Vec3::Zero();      // relative position the window measures displacement from
  bool sliding = false;          // friction on the cone (kinetic) at the last pass

  // First evaluation in a substep: continues the friction window when the contact is still
  // `in_touch` at this substep start, else opens a new one. Returns true for a new
  // window: the caller then sets `base` from the positions at the substep start. Passing the
  // substep stamp as the step gives a window of one substep.
  //
  // `slip_ends_window`: a contact that slid (kinetic, on the cone) at the last substep's end
  // opens a new window, so the slip stays motion. A window that ran on would measure that slip
  // as displacement still to undo, and once its cone had grown with the substeps' normal
  // corrections, static friction would pull the particle back to where the window began: several
  // substeps' slip undone in one, which the velocity update turns into a speed of slip / h
  // against the motion. A T-shirt lying on a table (config/tshirt.yaml) never came to rest that
  // way: 23-32 particles kept moving at up to 0.8 m/s at 20 substeps, and at 30 and 40 substeps,
  // where h is smaller, 500-1200 reached 9-15 m/s (doc/journal.md, "2026-11-28: Friction that gave
  // slip back"). Obstacle contacts pass true. Particle-particle contacts pass false: in a granular
  // pile the slip that one Gauss-Seidel pass leaves is what the running window catches up (above),
  // and with a new window after each slip the pile's angle spread from 25.4-28.9 to 20.9-27.6 deg
  // over 10 to 40 substeps (test_granular.cpp).
  bool beginSubstep(int substep_stamp, int step_stamp, bool in_touch, bool slip_ends_window) {
    if (substep == substep_stamp) return false;
    const bool continuing = window == step_stamp && in_touch && !(sliding && slip_ends_window);
    sliding = false;
    if (continuing) {
      window_depth += depth;
    } else {
      window = step_stamp;
      window_depth = 0.0;
      friction.setZero();
    }
    depth = 0.0;
    substep = substep_stamp;
    return !continuing;
  }
  // The seed's d: the normal correction resolved over the window.
  double frictionDepth() const { return window_depth + depth; }
  void forget() { substep = window = -1; }
};

// A contact within this fraction of its contact distance at a substep start counts as still in
// touch (ContactState::beginSubstep).
constexpr double kTouchGap = 0.05;

// Projected Gauss-Seidel on a unilateral contact (C >= 0): the correction this pass for the current
// value c of C, given what the contact has already pushed this substep (state.depth). A
// penetrating contact is pushed out by -c; a separated one that pushed earlier in the substep
// gives back up to what it pushed (the total stays >= 0: a contact never pulls). With one pass
// this is the seed's projection; with more, the total converges to the contact's multiplier
// instead of summing every back-and-forth of the relaxation, so the friction bound mu d does not
// grow with the pass count. Updates the state and returns the increment.
inline double contactIncrement(double c, ContactState& state) {
  const double increment = std::max(-c, -state.depth);
  state.depth += increment;
  return increment;
}

// Penetration a contact may keep during a step: the overlap left at the step start after
// pre-stabilisation, when deeper than the slop (a fraction of the contact distance). Such an
// overlap is only kept from growing and is removed by pre-stabilisation at the next step start,
// without velocity (Macklin et al. 2014, sec. 4.4), instead of by the projection, whose correction
// would become velocity ("explosive popping"). Zero for every contact that is not initially deep.
inline double allowanceFor(double overlap, double contact_distance, double slop) {
  return overlap > slop * contact_distance ? overlap : 0.0;
}

// Position-level Coulomb friction (collision seed, eq. friction_correction; Bender, Mueller,
// Macklin 2017, eqs. 27-28). `relative` is the relative displacement of the two sides over the
// friction window, Delta p_rel = (p*_i - p_i) - (p*_j - p_j); state.frictionDepth() the penetration
// d resolved in it. Returns the increment of relative correction to apply now (the caller
// distributes it by inverse mass).
//
// The seed's law for one pass: the correction is -Delta p_t (static) when |Delta p_t| <= mu_s d,
// else -Delta p_t mu_k d / |Delta p_t| (kinetic), with Delta p_t the tangential part of
// Delta p_rel. Over several passes and substeps the correction is accumulated (state.friction) and
// the total kept inside the friction cone, as projected Gauss-Seidel does with contact impulses:
// each pass asks for the accumulated correction plus whatever tangential motion is left, and the
// total is scaled back to mu_k d when it exceeds mu_s d. One pass gives exactly the seed's
// formula; more converge to the Coulomb answer even when another constraint (a floor under the
// lower of two stacked particles) undoes part of the correction in between.
inline Vec3 frictionCorrection(const Vec3& relative, ContactState& state,
                               const Friction& friction) {
  const Vec3& n = state.normal;
  const Vec3 tangential = relative - relative.dot(n) * n;  // Delta p_t left now
  const Vec3 applied = state.friction - state.friction.dot(n) * n;
  Vec3 total = applied - tangential;
  const double length = total.norm();
  const double depth = state.frictionDepth();
  state.sliding = length > friction.static_coefficient * depth;
  if (state.sliding) total *= friction.kinetic_coefficient * depth / length;  // on the cone
  state.friction = total;
  return total - applied;
}

}  // namespace pbd_cloth
