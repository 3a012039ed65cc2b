// The forces constraints and contacts exert on kinematic particles (pins, grippers).
#include "pbd_cloth/solver/solver.h"

#include <algorithm>

#include "pbd_cloth/constraints/flat_hinges.h"
#include "pbd_cloth/solver/solver_terms.h"

namespace pbd_cloth {

// The kinematic set is fixed during a step: the stretch constraints and hinges that join a
// kinematic to a free particle are listed once, so the reactions cost nothing for the others.
void Solver::startReactions(const Particles& p, const ClothTopology& topology, bool list) {
  std::fill(reaction_.begin(), reaction_.end(), Vec3::Zero());
  for (int i = 0; i < p.size(); ++i) {
    if (p.inverse_mass[i] == 0.0) start_velocity_[i] = p.velocity[i];
  }
  if (!list) return;  // the kinematic set of the last step
  kinematic_particles_.clear();
  for (int i = 0; i < p.size(); ++i) {
    if (p.inverse_mass[i] == 0.0) kinematic_particles_.push_back(i);
  }
  kinematic_stretch_.clear();
  kinematic_bend_.clear();
  if (config_.method == Method::kMassSpring) return;  // its springs report through force_
  const int stretch_count = static_cast<int>(topology.stretch.size());
  for (int c = 0; c < stretch_count; ++c) {
    const DistanceConstraint& con = topology.stretch[c];
    if ((p.inverse_mass[con.i] == 0.0) != (p.inverse_mass[con.j] == 0.0)) {
      kinematic_stretch_.push_back(c);
    }
  }
  if (bend_compliance_ < 0.0) return;
  const int bend_count = static_cast<int>(topology.bend.size());
  for (int c = 0; c < bend_count; ++c) {
    if (joinsKinematicToFree(topology.bend[c], p.inverse_mass.data())) kinematic_bend_.push_back(c);
  }
}

// After a substep's passes: each listed constraint's multiplier, summed over the passes, times
// its gradient at the kinematic particle (stretch: +-n; hinge: scale K_k) is the reaction there.
// Read after the passes instead of inside the projection loops, which stay as they are.
void Solver::addMultiplierReactions(const Particles& p, const ClothTopology& topology) {
  const PositionColumns columns = link_positions_.columns();
  auto position = [&](int i) {
    return in_columns_ ? Vec3(columns.x[i], columns.y[i], columns.z[i]) : p.position[i];
  };
  for (int c : kinematic_stretch_) {
    const DistanceConstraint& con = topology.stretch[c];
    const Vec3 delta = position(con.i) - position(con.j);
    const double length = delta.norm();
    if (length < kMinLength) continue;
    const Vec3 reaction = (stretchLambda(c, topology) / length) * delta;  // lambda grad_i C
    if (p.inverse_mass[con.i] == 0.0) {
      reaction_[con.i] += reaction;
    } else {
      reaction_[con.j] -= reaction;
    }
  }
  for (int c : kinematic_bend_) {
    const BendConstraint& con = topology.bend[c];
    for (int v = 0; v < 4; ++v) {
      const int i = con.index[v];
      if (p.inverse_mass[i] == 0.0) reaction_[i] += (con.scale * con.weight[v]) * bend_lambda_[c];
    }
  }
}

// Impulse over the step = sum of reactions / h (each is a force times h^2, applied once per
// substep); the force is that impulse / dt. The kinematic particle itself adds its weight and
// loses the momentum its prescribed motion gained.
void Solver::finishReactions(double dt, double h, const Particles& p,
                             const Collisions& collisions) {
  const double scale = 1.0 / (h * dt);
  const Vec3Array& contacts = collisions.kinematicReaction();
  for (int i = 0; i < p.size(); ++i) {
    if (p.inverse_mass[i] != 0.0) {
      constraint_force_[i].setZero();
      support_force_[i].setZero();
      continue;
    }
    constraint_force_[i] = scale * (reaction_[i] + contacts[i]);
    support_force_[i] = constraint_force_[i] +
                        p.mass[i] * (config_.gravity - (p.velocity[i] - start_velocity_[i]) / dt);
  }
}

}  // namespace pbd_cloth
