// The hinges' bending vectors, read by the projection (bend_projection.cpp) and by the explicit
// baseline's bending springs (mass_spring_stepper.cpp).
#pragma once

#include "pbd_cloth/model/particles.h"
#include "pbd_cloth/solver/solver_terms.h"

namespace pbd_cloth {

// The mean-curvature vector b = sum_k K_k x_k of a hinge, computed as sum_{k>0} K_k (x_k - x_0)
// (the weights sum to zero): the same value, without the cancellation of large coordinates that
// would leave ~1e-12 m of noise in a flat hinge 1e4 m from the origin.
inline Vec3 bendVector(const BendConstraint& con, const Particles& p) {
  const Vec3& x0 = p.position[con.index[0]];
  return con.weight[1] * (p.position[con.index[1]] - x0) +
         con.weight[2] * (p.position[con.index[2]] - x0) +
         con.weight[3] * (p.position[con.index[3]] - x0);
}

// The rest bending vector of a curved mesh hinge carried into the current positions: b0 = sum of
// its components along each triangle's current frame (edge, in-plane normal, normal), averaged
// over the two triangles so neither is preferred. Treated as fixed within one projection (its
// dependence on the positions is left out of the gradient): the constraint stays linear with the
// vector multiplier of the flat model, and at the rest shape, in any pose, b = b0' exactly.
inline Vec3 restBendVector(const BendConstraint& con, const BendRest& rest, const Particles& p) {
  const Vec3& x0 = p.position[con.index[0]];
  const Vec3 edge = p.position[con.index[1]] - x0;
  const double length = edge.norm();
  if (!(length > kMinLength)) return Vec3::Zero();
  const Vec3 t = edge / length;
  Vec3 target = Vec3::Zero();
  for (int side = 0; side < 2; ++side) {
    Vec3 n = t.cross(p.position[con.index[2 + side]] - x0);
    const double norm = n.norm();
    if (!(norm > kMinLength * length)) continue;  // collapsed triangle: no frame this time
    n /= side == 0 ? norm : -norm;
    const Vec3& c = side == 0 ? rest.in_first : rest.in_second;
    target += 0.5 * (c.x() * t + c.y() * n.cross(t) + c.z() * n);
  }
  return target;
}

}  // namespace pbd_cloth
