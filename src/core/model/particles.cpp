#include "pbd_cloth/model/particles.h"

#include <algorithm>

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

bool ClothTopology::meshNear(int a, int b) const {
  if (a == b) return true;
  if (near_offsets.empty()) return false;
  const auto begin = near_list.begin() + near_offsets[a],
             end = near_list.begin() + near_offsets[a + 1];
  return std::binary_search(begin, end, b);
}

}  // namespace pbd_cloth
