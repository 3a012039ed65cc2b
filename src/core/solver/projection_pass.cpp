// A substep's constraint passes (position-based methods): levels, stretch, bending, tethers,
// contacts, and the Jacobi ordering's accumulation.
#include "pbd_cloth/solver/solver.h"

#include <algorithm>
#include <cmath>

#include "pbd_cloth/constraints/tether_projection.h"
#include "pbd_cloth/solver/rod_stepper.h"
#include "pbd_cloth/solver/scoped_timer.h"

namespace pbd_cloth {

// The constraint passes of a substep (position-based methods: xpbd, pbd, verlet).
void Solver::projectSubstep(double h, Particles& p, const ClothTopology& topology,
                            Collisions& collisions) {
  ScopedTimer timer(stats_.project_time);
  // XPBD multipliers start at zero every substep (Small Steps, Algorithm 1). The flat links'
  // first pass writes theirs (projectStretch, lambda_from_zero); the others are cleared here.
  if (config_.ordering == Ordering::kJacobi || !fastStretch(topology)) {
    std::fill(stretch_lambda_.begin(), stretch_lambda_.end(), 0.0);
  }
  // The flat hinges' first pass writes theirs (projectFlatHinges, lambda_from_zero).
  if (!flatBend(topology)) std::fill(bend_lambda_.begin(), bend_lambda_.end(), Vec3::Zero());
  // The ropes' segments: their orientations predicted as the particles were (rod_stepper.h).
  if (hasRopes()) {
    for (Rod& rope : *ropes_) predictRodOrientations(rope, h, dampingFactor(h));
  }
  for (int pass = 0; pass < config_.iterations; ++pass) {
    ++stats_.iterations;
    const double max_change =
        projectPass(h, p, topology, collisions, pass == 0, pass + 1 == config_.iterations);
    // Adaptive count (seed: "measuring the change from last iteration").
    if (tracksLargestChange() && max_change < config_.tolerance) break;
  }
  if (hasRopes()) {
    for (Rod& rope : *ropes_) updateRodAngularVelocities(rope, h);
  }
  addMultiplierReactions(p, topology);
}

double Solver::projectPass(double h, Particles& p, const ClothTopology& topology,
                           Collisions& collisions, bool first_pass, bool last_pass) {
  // The count of the last pass is what the step reports: constraints still degenerate at its end.
  degenerate_.start();
  // Long-range levels first (solver.levels): they remove in one projection a stretch spread over
  // many links, which the cloth's own sweep carries one link per pass. Off while the cloth is
  // compliant (they are inextensible); the explicit springs do not come here.
  double max_change = 0.0;
  if (coarse_.levelCount() > 0 && stretch_compliance_ == 0.0) {
    max_change = in_columns_
                     ? coarse_.project(link_positions_.columns(), config_.simd,
                                       tracksLargestChange(), config_.avx512)
                     : coarse_.project(p, config_.simd, tracksLargestChange(), config_.avx512);
  }
  max_change = std::max(max_change, projectStretch(h, p, topology, first_pass));
  max_change = std::max(max_change, projectBend(h, p, topology, first_pass, last_pass));
  if (config_.ordering == Ordering::kJacobi) applyJacobi(p, max_change);
  max_change = std::max(max_change, projectTethers(p, topology));
  if (hasRopes()) max_change = std::max(max_change, projectRopes(h, p, first_pass));
  // Contacts last in each pass so the positions a pass ends with are free of penetration.
  // Timed on their own: the narrow phase is the part of a pass a scene's collisions add.
  ScopedTimer timer(stats_.contact_time);
  max_change = std::max(max_change, collisions.project(p, topology));
  return max_change;
}

// Long-range attachments (Kim et al. 2012): unilateral, only the free particle moves, so a
// tether never fights the anchor. A particle with several anchors must end inside the
// intersection of their balls, and projecting onto one ball can push it out of another: its
// tethers (contiguous in the list) are solved together, by rounds of a two-constraint active set:
// a = the most violated tether; if the projection into a's ball violates another, b = the worst of
// those, and the particle goes to the nearest point of the lens of a and b. Two anchors (two pinned
// corners, the common case) are solved exactly in one round, including the touching balls of a
// taut row where plain alternating projections only creep towards the single feasible point.
//
// One tether, or two with both anchors kinematic (every particle of a cloth hung from two pins or
// held by two grippers), take the shortcuts of tether_projection.h: the same positions to the bit,
// without the square roots the rounds take twice.
double Solver::projectTethers(Particles& p, const ClothTopology& topology) {
  const std::vector<Tether>& tethers = topology.tethers;
  const std::size_t count = tethers.size();
  double max_change = 0.0, max_change_squared = 0.0;
  AnchorAxis axis;  // anchors stay put during the pass
  std::size_t end = 0;
  for (std::size_t begin = 0; begin < count; begin = end) {
    const int particle = tethers[begin].particle;
    end = begin + 1;
    while (end < count && tethers[end].particle == particle) ++end;
    if (p.inverse_mass[particle] == 0.0) continue;
    Vec3& x = p.position[particle];
    int first_round = 0;
    const Tether& t0 = tethers[begin];
    if (end - begin <= 2 && p.inverse_mass[t0.anchor] == 0.0) {
      double moved_squared = 0.0;
      if (end - begin == 1) {
        moved_squared = projectTetherSingle(x, p.mass[particle], p.position[t0.anchor],
                                            t0.max_length, reaction_[t0.anchor]);
        max_change_squared = std::max(max_change_squared, moved_squared);
        continue;
      }
      const Tether& t1 = tethers[begin + 1];
      if (p.inverse_mass[t1.anchor] == 0.0) {
        const bool settled = projectTetherPair(
            x, p.mass[particle], p.position[t0.anchor], t0.max_length, p.position[t1.anchor],
            t1.max_length, reaction_[t0.anchor], reaction_[t1.anchor], axis, moved_squared);
        max_change_squared = std::max(max_change_squared, moved_squared);
        if (settled) continue;
        first_round = 1;  // the rounds go on from the second, as they would have
      }
    }
    max_change = std::max(
        max_change, projectTetherRounds(x, p.mass[particle], &tethers[begin], tethers.data() + end,
                                        p.position, p.inverse_mass, reaction_, first_round));
  }
  return std::max(max_change, std::sqrt(max_change_squared));
}

// The ropes: each one direct solve of its rod (rod_constraints.h) on its particles, copied out of
// and back into `p` around it (a rope's particles are contiguous); held particles are those with
// inverse mass 0 now. Multipliers start at zero in the substep's first pass.
double Solver::projectRopes(double h, Particles& p, bool first_pass) {
  double max_change = 0.0;
  for (std::size_t r = 0; r < ropes_->size(); ++r) {
    Rod& rope = (*ropes_)[r];
    const int first = rope.first_particle;
    for (int k = 0; k < rope.size(); ++k) {
      rope.position[k] = p.position[first + k];
      rope.inverse_mass[k] = p.inverse_mass[first + k];
    }
    if (first_pass) {
      for (Vec3& lambda : rope.stretch_shear_lambda) lambda.setZero();
      for (Vec3& lambda : rope.bend_twist_lambda) lambda.setZero();
    }
    rope_solvers_[r].solve(rope, h);
    for (int k = 0; k < rope.size(); ++k) {
      max_change = std::max(max_change, (rope.position[k] - p.position[first + k]).norm());
      p.position[first + k] = rope.position[k];
    }
  }
  return max_change;
}

// Jacobi: every correction of a pass was computed from the same positions and is applied here at
// once. The averaging (jacobiScale) is already in each constraint's step; without averaging the
// corrections are simply summed (REFERENCE_CASES.md case 7: x <- (1 - K) d).
void Solver::applyJacobi(Particles& p, double& max_change) {
  for (int i = 0; i < p.size(); ++i) {
    if (jacobi_count_[i] == 0) continue;
    p.position[i] += jacobi_delta_[i];
    max_change = std::max(max_change, jacobi_delta_[i].norm());
    jacobi_delta_[i].setZero();
  }
}

// n_k of the Jacobi averaging: the stretch and bending constraints acting on each free particle.
// The kinematic set is fixed during a step, so this runs once per step.
void Solver::countJacobiConstraints(const Particles& p, const ClothTopology& topology) {
  std::fill(jacobi_count_.begin(), jacobi_count_.end(), 0);
  for (const DistanceConstraint& con : topology.stretch) {
    if (!p.isKinematic(con.i)) ++jacobi_count_[con.i];
    if (!p.isKinematic(con.j)) ++jacobi_count_[con.j];
  }
  if (bend_compliance_ < 0.0 || config_.method == Method::kMassSpring) return;
  for (const BendConstraint& con : topology.bend) {
    for (int v = 0; v < 4; ++v) {
      if (!p.isKinematic(con.index[v])) ++jacobi_count_[con.index[v]];
    }
  }
}

}  // namespace pbd_cloth
