#include "pbd_cloth/solver/mass_spring_stepper.h"

#include "pbd_cloth/solver/bending.h"

namespace pbd_cloth {

void MassSpringStepper::prepare(int particle_count) { force_.assign(particle_count, Vec3::Zero()); }

// Stable only while w_max h < 2 (REFERENCE_CASES.md case 8).
int MassSpringStepper::substep(const SolverConfig& config, double bend_compliance, double h,
                               double s_end, Particles& p, const ClothTopology& topology,
                               Collisions& collisions, Vec3Array& reaction,
                               DegenerateCount& degenerate) {
  const double k = config.spring_stiffness, damper = config.spring_damping;
  for (int i = 0; i < p.size(); ++i) force_[i] = p.mass[i] * config.gravity;
  degenerate.start();
  const int count = static_cast<int>(topology.stretch.size());
  for (int c = 0; c < count; ++c) {
    const DistanceConstraint& con = topology.stretch[c];
    const Vec3 delta = p.position[con.i] - p.position[con.j];
    const double length = delta.norm();
    if (length < kMinLength) {  // coincident: no direction, reported as in projectStretch
      degenerate.note(c);
      continue;
    }
    const Vec3 n = delta / length;
    const double relative_speed = (p.velocity[con.i] - p.velocity[con.j]).dot(n);
    const Vec3 f = (-k * (length - con.rest_length) - damper * relative_speed) * n;
    force_[con.i] += f;
    force_[con.j] -= f;
  }
  if (bend_compliance >= 0.0) {
    // Bending springs on the isometric energy E = k_b / 2 scale^2 |b|^2: F_k = -k_b scale^2 K_k b.
    const bool has_rest = !topology.bend_rest.empty();
    for (std::size_t c = 0; c < topology.bend.size(); ++c) {
      const BendConstraint& con = topology.bend[c];
      const Vec3 b = has_rest && topology.bend_rest[c].curved
                         ? Vec3(bendVector(con, p) - restBendVector(con, topology.bend_rest[c], p))
                         : bendVector(con, p);
      if (b.norm() < kMinLength) continue;  // flat: no force but rounding noise
      const Vec3 f = -config.bend_spring_stiffness * con.scale * con.scale * b;
      for (int v = 0; v < 4; ++v) force_[con.index[v]] += con.weight[v] * f;
    }
  }
  // A kinematic particle's springs act on it like on any other; only it does not move. Their
  // force, times h^2, is its reaction (kg m) in the units of the projected constraints.
  for (int i = 0; i < p.size(); ++i) {
    if (p.inverse_mass[i] != 0.0) continue;
    reaction[i] += (h * h) * (force_[i] - p.mass[i] * config.gravity);
  }
  const double keep = velocityKept(config.damping, h);
  for (int i = 0; i < p.size(); ++i) {
    p.substep_start[i] = p.position[i];
    if (p.inverse_mass[i] == 0.0) {
      p.position[i] = (1.0 - s_end) * p.kinematic_from[i] + s_end * p.kinematic_to[i];
      continue;
    }
    p.velocity[i] = keep * p.velocity[i] + h * p.inverse_mass[i] * force_[i];
    p.position[i] += h * p.velocity[i];  // x~ = start + h v, as updateVelocities reads it
  }
  int passes = 0;
  for (int pass = 0; pass < config.iterations; ++pass) {
    ++passes;
    if (collisions.project(p, topology) <= config.tolerance) break;
  }
  return passes;
}

}  // namespace pbd_cloth
