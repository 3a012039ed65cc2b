// A rope or cable as a Cosserat rod (Kugelstadt and Schoemer 2016, "Position and orientation
// based Cosserat rods"): particles x_0 .. x_N joined by N segments, each with an orientation q_i
// (a unit quaternion) whose third director d3 = q_i e_z runs along the segment and whose first two
// (d1, d2) are the cross-section's axes. Stretch and shear tie each segment's particles to its
// director (constraints/rod_constraints.h); bending and twist tie neighbouring orientations. The
// stiffness comes from the material (EA, GA, EI = E pi r^4 / 4, GJ = G pi r^4 / 2) through XPBD
// compliance, so a rod behaves the same at any substep count.
// Particles and segments in flat arrays, as the cloth's (model/particles.h).
#pragma once

#include <Eigen/Geometry>
#include <vector>

#include "pbd_cloth/geometry/vector_types.h"

namespace pbd_cloth {

using Quaternion = Eigen::Quaterniond;

// What a rope is made of (ropes: in a scene): a solid circular cross-section.
struct RodMaterial {
  double radius = 0.005;       // m
  double density = 1000.0;     // kg/m^3
  double young_modulus = 1e7;  // Pa, E: stretch (EA) and bending (EI)
  double shear_modulus = 4e6;  // Pa, G: shear (GA) and twist (GJ)
  // m/N: the stretch and shear compliance of a unit length, replacing 1 / EA and 1 / GA; 0 =
  // inextensible; negative (the default): from E and G.
  double stretch_compliance = -1.0;
};

// The stiffnesses of a cross-section (per unit length).
struct RodStiffness {
  double stretch = 0.0;  // EA (N), or 1 / stretch_compliance; infinite when 0
  double shear = 0.0;    // GA (N)
  double bend = 0.0;     // EI (N m^2), about d1 and d2
  double twist = 0.0;    // GJ (N m^2), about d3
};
RodStiffness rodStiffness(const RodMaterial& material);

struct Rod {
  // Particles 0 .. N.
  Vec3Array position, velocity, substep_start;
  std::vector<double> mass, inverse_mass;  // kg, 1/kg; inverse 0 = kinematic
  // Segments 0 .. N-1: segment i joins particles i and i + 1.
  std::vector<Quaternion> orientation, orientation_start;
  Vec3Array angular_velocity;  // rad/s, world frame
  std::vector<double> rest_length;
  // Inverse rotational inertia about d1 and d2 (bending) and about d3 (twist); 0 = kinematic.
  std::vector<double> inverse_inertia_bend, inverse_inertia_twist;
  // Joints 0 .. N-2: joint k between segments k and k + 1. Rest Darboux vector (1/m), in the
  // frame of segment k: (2 / lbar) Im(conj(q_k) q_{k+1}) at rest, lbar the mean of the two lengths.
  Vec3Array rest_darboux;
  // XPBD multipliers of the substep: stretch-shear (world frame, per segment) and bend-twist
  // (frame of segment k, per joint).
  Vec3Array stretch_shear_lambda, bend_twist_lambda;
  RodStiffness stiffness;
  double radius = 0.0;
  // In a scene: the index of particle 0 among the Simulation's particles (the cloth's, then each
  // rope's in order). The step works on those particles; position, velocity and the masses here
  // are the rope's own copy only for a rod stepped alone (stepRod).
  int first_particle = 0;

  int segments() const { return static_cast<int>(orientation.size()); }
  int size() const { return static_cast<int>(position.size()); }
  // Holds particle i where it is (pinned, clamped); with its segment(s), their orientation too.
  void fixParticle(int i);
  void fixSegment(int i);
};

// A rod placed through `points` (at least 2): each segment's d3 along it, the frames carried from
// one segment to the next by the smallest rotation (parallel transport: no twist), the first one's
// d1 whatever the shortest rotation from e_z gives. At rest it is straight and untwisted (rest
// Darboux vectors zero: a rope keeps no bend), each segment as long as placed.
Rod makeRod(const Vec3Array& points, const RodMaterial& material);
// A straight rod from `start` to `end` in `segments` equal segments.
Rod makeStraightRod(const Vec3& start, const Vec3& end, int segments, const RodMaterial& material);

// q <- normalize(q + 1/2 (0, rotation) q): a small rotation (world frame, rad) applied to an
// orientation, as the solve's corrections and a substep's spin h omega are.
void applySmallRotation(Quaternion& q, const Vec3& rotation);

// The Darboux vector of joint k now: (2 / lbar) Im(conj(q_k) q_{k+1}), the shorter rotation.
Vec3 darbouxVector(const Rod& rod, int joint);

}  // namespace pbd_cloth
