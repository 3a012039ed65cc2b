// The stretch constraints' projection (seed eq. C2; XPBD eq. 18), Gauss-Seidel or Jacobi.
#include "pbd_cloth/solver/solver.h"

#include <algorithm>
#include <cmath>

#include "pbd_cloth/solver/solver_terms.h"

namespace pbd_cloth {

// Jacobi with averaging scales constraint c's multiplier step by w / max_k n_k over its free
// particles k (n_k = number of constraints on particle k, w = solver.relaxation). This is the
// averaging of Bender et al. 2017, eq. 48 (dx_i = w / n_i sum_c dx_i^c) applied per constraint
// instead of per particle: both ends get the same scaled step and lambda accumulates exactly what
// was applied, so momentum is conserved and the fixed point is the XPBD solution
// x - x~ = M^-1 grad C^T lambda, C + alpha~ lambda = 0. Per-particle averaging moves a particle
// with n_i constraints as if its mass were n_i / w times larger, and an XPBD chain then settles at
// n_i / w times the stretch alpha T (REFERENCE_CASES.md case 6). For one particle under K
// constraints the two are the same: x <- (1 - w) d (case 7). For distance constraints (unit
// gradients) it converges for 0 < w < 2: linearized, the scaled step is a Richardson iteration on
// (J M^-1 J^T + alpha~) lambda = -C with the diagonal preconditioner D = (w_i + w_j + alpha~) max n
// / w, and 2D - A is diagonally dominant (Gershgorin), hence positive definite.
double Solver::jacobiScale(int i, int j) const {
  return config_.relaxation / std::max({1, jacobi_count_[i], jacobi_count_[j]});
}

// Stretch constraints C = |x_i - x_j| - l0 (seed eq. C2). verlet: rigid projection weighted by
// inverse mass (the seed's stick, x1 -= w1/(w1+w2) C n); pbd: the same scaled by k';
// xpbd: dlambda = (-C - alpha~ lambda) / (w_i + w_j + alpha~), alpha~ = alpha / h^2 (XPBD eq. 18).
double Solver::projectStretch(double h, Particles& p, const ClothTopology& topology,
                              bool first_pass) {
  const bool xpbd = config_.method == Method::kXpbd;
  const bool jacobi = config_.ordering == Ordering::kJacobi;
  const bool average = jacobi && config_.jacobi_averaging;
  const double alpha = stretchAlpha(h);
  const double k = config_.method == Method::kPbd ? pbdStiffness(config_.stretch_stiffness) : 1.0;
  const int count = static_cast<int>(topology.stretch.size());
  if (!jacobi && fastStretch(topology)) {
    // Gauss-Seidel: the flat, batched links (stretch_links.h), phase by phase; the tasks of a
    // phase share no particle, so threads run them side by side with the sequential result.
    StretchProjection how;
    how.alpha = alpha;
    how.stiffness = k;
    how.simd = config_.simd;
    how.avx512 = config_.avx512;
    how.track_change = tracksLargestChange();
    how.lambda_from_zero = first_pass;
    // The sweep works on the positions in columns (stretch_links.h, PositionColumns): copied in
    // and back out around it, which costs a small part of what the columns save the sweep. The
    // copies run on this thread: with solver.threads 2 one more meeting of the threads for each
    // cost more than the half copy it saved (doc/journal.md, "2026-11-29: Positions in columns").
    // In a step of links alone they are there already (linksAlone).
    double* x = p.position.front().data();
    const PositionColumns columns = link_positions_.columns();
    if (!in_columns_) positionsToColumns(x, 0, p.size(), columns, config_.simd);
    StretchPassResult result;
    const int threads = pool_.threads();
    for (int phase = 0; phase < stretch_links_.phaseCount(); ++phase) {
      const int* range = &thread_tasks_[phase * (threads + 1)];
      auto job = [&](int t) {
        thread_results_[t] = projectStretchLinks(
            stretch_links_, stretch_links_.task_batch[range[t]],
            stretch_links_.task_batch[range[t + 1]], how, columns, link_lambda_.data());
      };
      pool_.run(job);
      for (int t = 0; t < threads; ++t) result.merge(thread_results_[t]);
    }
    if (!in_columns_) positionsFromColumns(columns, 0, p.size(), x, config_.simd);
    if (result.degenerate > 0) {
      if (degenerate_.count == 0) {
        degenerate_.first = stretch_links_.original[result.first_degenerate];
      }
      degenerate_.count += result.degenerate;
    }
    return result.max_change;
  }
  double max_change = 0.0;
  for (int c = 0; c < count; ++c) {
    const DistanceConstraint& con = topology.stretch[c];
    const double wi = p.inverse_mass[con.i], wj = p.inverse_mass[con.j];
    const double w = wi + wj;
    if (w < kMinInverseMass) continue;
    const Vec3 delta = p.position[con.i] - p.position[con.j];
    const double length = delta.norm();
    if (length < kMinLength) {
      // Coincident particles: no direction to push along. Skipped for this pass (the other
      // constraints pull them apart) and reported, so it does not pass silently.
      degenerate_.note(c);
      continue;
    }
    const Vec3 n = delta / length;
    const double constraint = length - con.rest_length;
    double dlambda =
        xpbd ? (-constraint - alpha * stretch_lambda_[c]) / (w + alpha) : -k * constraint / w;
    if (average) dlambda *= jacobiScale(con.i, con.j);
    stretch_lambda_[c] += dlambda;
    const Vec3 correction = dlambda * n;
    max_change = std::max(max_change, std::abs(dlambda) * std::max(wi, wj));
    if (jacobi) {
      jacobi_delta_[con.i] += wi * correction;
      jacobi_delta_[con.j] -= wj * correction;
    } else {
      p.position[con.i] += wi * correction;
      p.position[con.j] -= wj * correction;
    }
  }
  return max_change;
}

}  // namespace pbd_cloth
