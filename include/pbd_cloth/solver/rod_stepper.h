// A rod's step (model/rod.h) as the cloth's: for each substep predict (particles: v += h g, x += h
// v; segments: q += h/2 (0, omega) q), solve the constraints once (XPBD, multipliers from zero
// each substep: Small Steps, Algorithm 1; one direct solve, constraints/rod_constraints.h), update
// velocities (v = (x - x_start) / h, omega = 2
// Im(q conj(q_start)) / h). Kinematic particles and segments (inverse mass or inertia 0) stay
// where they are. The gyroscopic term of a segment's spin is left out (a thin rod's inertia about
// its axis is tiny and its spin slow in any robot's cable).
#pragma once

#include "pbd_cloth/constraints/rod_constraints.h"
#include "pbd_cloth/model/rod.h"

namespace pbd_cloth {

struct RodStepSettings {
  int substeps = 20;
  Vec3 gravity{0.0, 0.0, -9.81};
  double damping = 0.0;  // 1/s, on linear and angular velocity alike
};

// The segments' part of a substep, which the cloth's solver runs for a scene's ropes around its own
// prediction and velocity update of their particles: predict (orientation_start = q, omega *=
// keep, q += h/2 (0, omega) q), and after the solve, omega = 2 Im(q conj(q_start)) / h.
// Kinematic segments (both inverse inertias 0) stay as they are.
void predictRodOrientations(Rod& rod, double h, double keep);
void updateRodAngularVelocities(Rod& rod, double h);

// `solver` holds the solve's room (RodSolver::prepare once for the rod: no allocation here).
void stepRod(Rod& rod, double dt, const RodStepSettings& settings, RodSolver& solver);

}  // namespace pbd_cloth
