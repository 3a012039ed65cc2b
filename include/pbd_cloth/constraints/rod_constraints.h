// The constraints of a Cosserat rod (model/rod.h) and their solve: XPBD (Macklin et al. 2016)
// on the whole rod at once, one direct solve a substep (Deul, Kugelstadt, Weiler and Bender 2018,
// "Direct position-based solver for stiff rods"): a rod is a chain, so its system is block
// tridiagonal and solves in time linear in its segments. A Gauss-Seidel sweep instead carries a
// moment one joint a pass: a 40-segment cantilever at 1,000 substeps still sagged 42 % more than
// beam theory (doc/journal.md, "2026-12-08: Cosserat rods").
//
// Stretch and shear, per segment s (Kugelstadt and Schoemer 2016, eq. 31):
//   C_s = (x_{s+1} - x_s) / l - d3(q_s) (world frame); energy l / 2 (EA C_par^2 + GA |C_perp|^2),
//   C_par along d3 (stretch), C_perp across it (shear). Gradient: -I / l, I / l on the particles,
//   [d3]x on a small rotation dtheta of the segment (d(d3) = dtheta x d3).
// Bend and twist, per joint k of segments k and k + 1 (eq. 32-33):
//   C_k = Omega - Omega_0, Omega = (2 / lbar) Im(conj(q_k) q_{k+1}) (segment k's frame, 1/m);
//   energy lbar / 2 (EI (C_1^2 + C_2^2) + GJ C_3^2). Gradient: -R_k^T / lbar on dtheta_k and R_k^T
//   / lbar on dtheta_{k+1} (to first order in the joint's own rotation).
// Each substep: (J W J^T + alpha~) dlambda = -C - alpha~ lambda with alpha~ = compliance / h^2,
// then x += W J^T dlambda; W holds the particles' inverse masses and the segments' inverse
// inertias (world frame), zero where kinematic.
#pragma once

#include <Eigen/Core>
#include <vector>

#include "pbd_cloth/model/rod.h"

namespace pbd_cloth {

class RodSolver {
 public:
  // Room for a rod of `segments` segments: solve() allocates nothing.
  void prepare(int segments);
  // One direct solve of every constraint of the rod (substep h), applied to its particles and
  // orientations; the multipliers add up in rod.stretch_shear_lambda and rod.bend_twist_lambda.
  void solve(Rod& rod, double h);

 private:
  using Matrix6 = Eigen::Matrix<double, 6, 6>;
  using Vector6 = Eigen::Matrix<double, 6, 1>;
  // Unit s: rows 0-2 the stretch-shear of segment s, rows 3-5 the bend-twist of joint s (none
  // for the last segment: identity rows). diagonal_[s] its block, upper_[s] its coupling to unit
  // s + 1; the forward elimination overwrites them.
  std::vector<Matrix6, Eigen::aligned_allocator<Matrix6>> diagonal_, upper_;
  std::vector<Vector6, Eigen::aligned_allocator<Vector6>> rhs_;
  std::vector<Eigen::Matrix3d, Eigen::aligned_allocator<Eigen::Matrix3d>> frame_, inverse_inertia_;
  Vec3Array turn_;
};

// The moment (N m) joint k carries now, in segment k's frame: K (Omega - Omega_0), K = (EI, EI,
// GJ): the bending moments about d1 and d2 and the twisting moment about d3.
Vec3 rodJointMoment(const Rod& rod, int joint);

}  // namespace pbd_cloth
