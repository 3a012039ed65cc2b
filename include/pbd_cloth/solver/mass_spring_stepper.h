// solver.method mass_spring: the explicit baseline, a stepper of its own beside the position-based
// methods. Spring and damper forces, then symplectic Euler; contacts are still projected, so a
// comparison measures the cloth model, not the collision handling.
#pragma once

#include "pbd_cloth/collision/collisions.h"
#include "pbd_cloth/model/particles.h"
#include "pbd_cloth/solver/solver_settings.h"
#include "pbd_cloth/solver/solver_terms.h"

namespace pbd_cloth {

class MassSpringStepper {
 public:
  // Sizes the force accumulator (allocates; a substep does not).
  void prepare(int particle_count);
  // One substep of h ending at fraction s_end of the step: forces, the free particles' velocities
  // and positions (x~ = start + h v, as Solver::updateVelocities reads it), the kinematic ones at
  // their prescribed place, then the contact passes. Adds each kinematic particle's spring force
  // times h^2 into `reaction` (kg m) and counts coincident springs in `degenerate`. Returns the
  // passes run.
  int substep(const SolverConfig& config, double bend_compliance, double h, double s_end,
              Particles& p, const ClothTopology& topology, Collisions& collisions,
              Vec3Array& reaction, DegenerateCount& degenerate);

 private:
  Vec3Array force_;
};

}  // namespace pbd_cloth
