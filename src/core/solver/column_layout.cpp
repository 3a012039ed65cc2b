// A step of links alone keeps the particles in columns (stretch_links.h, PositionColumns).
#include "pbd_cloth/solver/solver.h"

namespace pbd_cloth {

// A step of links alone: nothing in a pass but the coarse levels and the flat links (no hinges,
// or tethers, and collisions that touch no particle: a cloth swinging free), Gauss-
// Seidel. Its positions, velocities and substep starts then stay in columns for the whole step
// (stateToColumns before the first prediction, stateFromColumns after the last update), where
// otherwise every pass copies the positions into the columns and back around the sweep: 13.5 % of
// the 100 x 100 swinging cloth's step (doc/journal.md, "2026-12-06: A step of links alone, in
// columns").
bool Solver::linksAlone(const Particles& p, const ClothTopology& topology,
                        const Collisions& collisions) const {
  return config_.method != Method::kMassSpring && config_.ordering != Ordering::kJacobi &&
         fastStretch(topology) && link_positions_.size() == p.size() && bend_compliance_ < 0.0 &&
         topology.tethers.empty() && !hasRopes() && collisions.touchesNoParticle(p, topology);
}

void Solver::stateToColumns(const Particles& p) {
  const int n = p.size();
  positionsToColumns(p.position.front().data(), 0, n, link_positions_.columns(), config_.simd);
  positionsToColumns(p.velocity.front().data(), 0, n, column_velocity_.columns(), config_.simd);
}

void Solver::stateFromColumns(Particles& p) {
  const int n = p.size();
  positionsFromColumns(link_positions_.columns(), 0, n, p.position.front().data(), config_.simd);
  positionsFromColumns(column_velocity_.columns(), 0, n, p.velocity.front().data(), config_.simd);
  positionsFromColumns(column_start_.columns(), 0, n, p.substep_start.front().data(), config_.simd);
}

}  // namespace pbd_cloth
