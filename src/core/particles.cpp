#include "pbd_cloth/particles.h"

namespace pbd_cloth {

void Particles::resize(int n) {
  position.assign(n, Vec3::Zero());
  velocity.assign(n, Vec3::Zero());
  substep_start.assign(n, Vec3::Zero());
  step_start.assign(n, Vec3::Zero());
  kinematic_from.assign(n, Vec3::Zero());
  kinematic_to.assign(n, Vec3::Zero());
  mass.assign(n, 0.0);
  inverse_mass.assign(n, 0.0);
  radius.assign(n, 0.0);
}

}  // namespace pbd_cloth
