// A Cosserat rod's substeps (rod_stepper.h).
#include "pbd_cloth/solver/rod_stepper.h"

#include <cmath>

#include "pbd_cloth/solver/solver_terms.h"

namespace pbd_cloth {

namespace {
bool kinematic(const Rod& rod, int s) {
  return rod.inverse_inertia_bend[s] == 0.0 && rod.inverse_inertia_twist[s] == 0.0;
}
}  // namespace

void predictRodOrientations(Rod& rod, double h, double keep) {
  for (int s = 0; s < rod.segments(); ++s) {
    rod.orientation_start[s] = rod.orientation[s];
    if (kinematic(rod, s)) continue;
    rod.angular_velocity[s] *= keep;
    applySmallRotation(rod.orientation[s], h * rod.angular_velocity[s]);
  }
}

void updateRodAngularVelocities(Rod& rod, double h) {
  for (int s = 0; s < rod.segments(); ++s) {
    if (kinematic(rod, s)) continue;
    Quaternion turn = rod.orientation[s] * rod.orientation_start[s].conjugate();
    if (turn.w() < 0.0) turn.coeffs() = -turn.coeffs();
    rod.angular_velocity[s] = (2.0 / h) * turn.vec();
  }
}

void stepRod(Rod& rod, double dt, const RodStepSettings& settings, RodSolver& solver) {
  const double h = dt / settings.substeps;
  const double keep = velocityKept(settings.damping, h);
  for (int substep = 0; substep < settings.substeps; ++substep) {
    for (int i = 0; i < rod.size(); ++i) {
      rod.substep_start[i] = rod.position[i];
      if (rod.inverse_mass[i] == 0.0) continue;
      rod.velocity[i] = keep * rod.velocity[i] + h * settings.gravity;
      rod.position[i] += h * rod.velocity[i];
    }
    predictRodOrientations(rod, h, keep);
    for (Vec3& lambda : rod.stretch_shear_lambda) lambda.setZero();
    for (Vec3& lambda : rod.bend_twist_lambda) lambda.setZero();
    solver.solve(rod, h);
    for (int i = 0; i < rod.size(); ++i) {
      if (rod.inverse_mass[i] == 0.0) continue;
      rod.velocity[i] = (rod.position[i] - rod.substep_start[i]) / h;
    }
    updateRodAngularVelocities(rod, h);
  }
}

}  // namespace pbd_cloth
