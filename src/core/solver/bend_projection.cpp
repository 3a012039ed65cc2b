// The hinges' projection: isometric bending as a vector constraint (XPBD eq. 18).
#include "pbd_cloth/solver/solver.h"

#include <algorithm>
#include <cmath>

#include "pbd_cloth/constraints/flat_hinges.h"
#include "pbd_cloth/solver/bending.h"
#include "pbd_cloth/solver/solver_terms.h"

namespace pbd_cloth {

// Isometric bending as the vector constraint C = scale b, b = sum_k K_k x_k (particles.h): linear
// in the positions, grad_k C = scale K_k I. A flat hinge (b = 0) gets no correction; nothing is
// divided by |b|, so there is no degenerate case.
double Solver::projectBend(double h, Particles& p, const ClothTopology& topology, bool first_pass,
                           bool last_pass) {
  if (bend_compliance_ < 0.0 || config_.method == Method::kMassSpring) return 0.0;
  const bool xpbd = config_.method == Method::kXpbd;
  const bool jacobi = config_.ordering == Ordering::kJacobi;
  const bool average = jacobi && config_.jacobi_averaging;
  const double alpha = xpbd ? bend_compliance_ / (h * h) : 0.0;
  const double k = xpbd ? 1.0 : pbdStiffness(config_.bend_stiffness);
  double max_change = 0.0;
  const int count = static_cast<int>(topology.bend.size());
  if (flatBend(topology)) return projectFlatBend(p, topology, first_pass, last_pass);
  const bool has_rest = !topology.bend_rest.empty();
  for (int c = 0; c < count; ++c) {
    const BendConstraint& con = topology.bend[c];
    double w = 0.0;
    for (int v = 0; v < 4; ++v) {
      w += p.inverse_mass[con.index[v]] * con.weight[v] * con.weight[v];
    }
    w *= con.scale * con.scale;
    if (w < kMinInverseMass) continue;
    // The vector constraint C = scale b (three rows, each with gradient scale K_k per vertex) has
    // the same energy as scale |b| but is linear in the positions: one projection solves it
    // exactly, and the multiplier is a vector, so a hinge that swings through flat keeps the
    // direction of its accumulated force instead of flipping the sign of a scalar lambda, and no
    // |b| is divided by. XPBD: dlambda = (-C - alpha lambda) / (w + alpha) (Macklin et al. 2016,
    // eq. 18), row by row with the common w.
    // Mesh hinges with a curved rest shape: C = scale (b - b0'), b0' the rest vector in the
    // hinge's current frames (restBendVector); flat hinges and the grid: C = scale b.
    const Vec3 constraint =
        has_rest && topology.bend_rest[c].curved
            ? Vec3(con.scale * (bendVector(con, p) - restBendVector(con, topology.bend_rest[c], p)))
            : Vec3(con.scale * bendVector(con, p));
    Vec3 dlambda = xpbd ? Vec3((-constraint - alpha * bend_lambda_[c]) / (w + alpha))
                        : Vec3((-k / w) * constraint);
    if (average) {
      dlambda *= std::min(jacobiScale(con.index[0], con.index[1]),
                          jacobiScale(con.index[2], con.index[3]));
    }
    bend_lambda_[c] += dlambda;
    const Vec3 direction = con.scale * dlambda;
    // |dx_k| = w_k |K_k| |direction|: one norm per hinge, not per vertex.
    double largest_weight = 0.0;
    for (int v = 0; v < 4; ++v) {
      const int i = con.index[v];
      const double factor = p.inverse_mass[i] * con.weight[v];
      largest_weight = std::max(largest_weight, std::abs(factor));
      if (jacobi) {
        jacobi_delta_[i] += factor * direction;
      } else {
        p.position[i] += factor * direction;
      }
    }
    max_change = std::max(max_change, largest_weight * direction.norm());
  }
  return max_change;
}

// The hinges of a flat rest shape (every grid hinge) in Gauss-Seidel order, with what is fixed
// for a step computed once in prepareBendStep (flat_hinges.h): the same projection as the loop of
// projectBend, with no division and no per-vertex weight arithmetic in the pass.
double Solver::projectFlatBend(Particles& p, const ClothTopology& topology, bool first_pass,
                               bool last_pass) {
  if (topology.bend.empty()) return 0.0;  // (and no multipliers to point at)
  double* x = p.position.front().data();
  const bool track_change = tracksLargestChange();
  // Hinges [begin, end) in order.
  auto sweep = [&](int begin, int end) {
    return projectFlatHinges(flat_hinges_.data() + begin, end - begin, first_pass, !last_pass,
                             track_change, config_.simd, config_.avx512, x,
                             bend_lambda_.front().data() + 3 * static_cast<std::size_t>(begin));
  };
  const int threads = pool_.threads();
  const std::vector<int>& task = topology.bend_task;
  if (threads == 1 || task.empty()) return sweep(0, static_cast<int>(topology.bend.size()));
  // The blocks' tasks, then the seams' (cloth_builder.cpp, groupHingesIntoTasks): each thread
  // a consecutive range of a group's tasks, in the order one thread runs them all.
  double max_change = 0.0;
  const int groups[3] = {0, topology.bend_blocks, static_cast<int>(task.size()) - 1};
  for (int g = 0; g < 2; ++g) {
    const int tasks = groups[g + 1] - groups[g];
    pool_.runRanges(tasks, [&](int first, int last, int t) {
      thread_results_[t].max_change = sweep(task[groups[g] + first], task[groups[g] + last]);
    });
    for (int t = 0; t < threads; ++t) {
      max_change = std::max(max_change, thread_results_[t].max_change);
    }
  }
  return max_change;
}

// XPBD's dlambda = (-k C - alpha~ lambda) / (w + alpha~) for C = scale b (eq. 18), split into
// what the step fixes: gain_k = -k scale K_k / (w + alpha~) and decay = alpha~ / (w + alpha~);
// corner k moves by w_k K_k scale dlambda (flat_hinges.h).
void Solver::prepareBendStep(const Particles& p, const ClothTopology& topology, double h) {
  const int count = static_cast<int>(topology.bend.size());
  if (static_cast<int>(flat_hinges_.size()) != count) return;
  const bool xpbd = config_.method == Method::kXpbd;
  const double alpha = xpbd ? bend_compliance_ / (h * h) : 0.0;
  const double k = xpbd ? 1.0 : pbdStiffness(config_.bend_stiffness);
  for (int c = 0; c < count; ++c) {
    flat_hinges_[c] =
        makeFlatHinge(topology.bend[c], p.inverse_mass.data(), alpha, k, kMinInverseMass);
  }
}

}  // namespace pbd_cloth
