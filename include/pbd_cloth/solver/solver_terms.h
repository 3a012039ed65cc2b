// Thresholds and counts the solver's units share.
#pragma once

#include <cmath>

namespace pbd_cloth {

// Below this length a distance constraint has no direction: skipped (coincident particles).
inline constexpr double kMinLength = 1e-12;
// Below this a constraint's generalized inverse mass is zero (all particles kinematic): skipped.
inline constexpr double kMinInverseMass = 1e-300;

// Velocity kept over a substep by the damping dv/dt = -c v, integrated exactly: e^{-c h}. Unlike
// 1 - c h it never turns negative and is the same for any split of a step into substeps.
inline double velocityKept(double damping, double h) { return std::exp(-damping * h); }

// Stretch constraints skipped in the current pass because their particles coincide, and the
// first of them; the last pass's figures become the step's stats.
struct DegenerateCount {
  int count = 0;
  int first = -1;
  void start() {
    count = 0;
    first = -1;
  }
  void note(int constraint) {
    if (count++ == 0) first = constraint;
  }
};

}  // namespace pbd_cloth
