// solver.chebyshev: the Chebyshev semi-iterative method over a substep's passes.
#include "pbd_cloth/solver/solver.h"

namespace pbd_cloth {

// One position a particle for each buffer while solver.chebyshev is on (jacobi_delta_ has
// the particle count prepare() saw); released while it is off.
void Solver::sizeChebyshevBuffers() {
  if (config_.chebyshev > 0.0) {
    chebyshev_current_.assign(jacobi_delta_.size(), Vec3::Zero());
    chebyshev_previous_.assign(jacobi_delta_.size(), Vec3::Zero());
  } else {
    Vec3Array().swap(chebyshev_current_);
    Vec3Array().swap(chebyshev_previous_);
  }
}

// Whether pass `pass` keeps the positions it starts from: every pass before the last one does, so
// that pass k >= 1 finds q^{k-1} in chebyshev_previous_.
bool Solver::chebyshevKeeps(int pass) const {
  return config_.chebyshev > 0.0 && pass + 1 < config_.iterations;
}

// solver.chebyshev: the Chebyshev semi-iterative method over a substep's passes (Wang 2015, "A
// Chebyshev Semi-Iterative Approach for Accelerating Projective and Position-based Dynamics").
// Pass k's result q^ is replaced by q^{k+1} = omega_{k+1} (q^ - q^{k-1}) + q^{k-1},
// with omega_1 = 2 / (2 - rho^2) at the first extrapolated pass and omega_{k+1} = 4 / (4 - rho^2
// omega_k) after it: the weights of the Chebyshev polynomials that damp every error mode whose
// factor per pass is at most rho. Pass 0 has no q^{k-1}, and the last pass is not extrapolated so
// that the substep ends with the contacts that pass projected (free of penetration) and the
// velocity update sees a projected state, not an extrapolated one. The multipliers are not
// extrapolated: a gripper's reported force (addMultiplierReactions) counts the passes' own
// corrections only.
// Returns omega_{k+1}, given the last pass's omega_k (unused at the first extrapolated pass).
double Solver::accelerate(int pass, double omega, Particles& p) {
  const double rho2 = config_.chebyshev * config_.chebyshev;
  omega = pass == 1 ? 2.0 / (2.0 - rho2) : 4.0 / (4.0 - rho2 * omega);
  pool_.runRanges(p.size(), [&](int begin, int end, int) {
    for (int i = begin; i < end; ++i) {
      if (p.inverse_mass[i] == 0.0) continue;  // kinematic: its path is prescribed
      p.position[i] = chebyshev_previous_[i] + omega * (p.position[i] - chebyshev_previous_[i]);
    }
  });
  return omega;
}

}  // namespace pbd_cloth
