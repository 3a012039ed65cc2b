// Ropes and cables as Cosserat rods (model/rod.h, constraints/rod_constraints.h,
// solver/rod_stepper.h), against beam theory.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "pbd_cloth/constraints/rod_constraints.h"
#include "pbd_cloth/solver/rod_stepper.h"

namespace pbd_cloth {
namespace {

constexpr double kPi = 3.14159265358979323846;

// A steel-stiff plastic rod: 1 m long, 5 mm radius, 1000 kg/m^3, E = 10 GPa, G = E / 2.6.
RodMaterial stiffRod() {
  RodMaterial m;
  m.radius = 0.005;
  m.density = 1000.0;
  m.young_modulus = 1e10;
  m.shear_modulus = 1e10 / 2.6;
  return m;
}

// The rod from x = -l/2 to L, its first particle and segment held: the clamp is the middle of
// the first segment (x = 0), so the free length is L (a clamp at the first particle would be
// half a segment behind the first joint's bending).
Rod clampedRod(double length, int segments, const RodMaterial& material) {
  const double l = length / (segments - 0.5);
  Rod rod = makeStraightRod(Vec3(-0.5 * l, 0.0, 1.0), Vec3(length, 0.0, 1.0), segments, material);
  rod.fixParticle(0);
  rod.fixSegment(0);
  return rod;
}

// Steps a rod `steps` steps of 1/60 s at `substeps` substeps with damping (to come to rest).
void settle(Rod& rod, int steps, int substeps, double damping,
            const Vec3& gravity = Vec3(0.0, 0.0, -9.81)) {
  RodStepSettings settings;
  settings.substeps = substeps;
  settings.damping = damping;
  settings.gravity = gravity;
  RodSolver solver;
  solver.prepare(rod.segments());
  for (int k = 0; k < steps; ++k) stepRod(rod, 1.0 / 60.0, settings, solver);
}

// A cantilever under its own weight q = rho A g: tip deflection q L^4 / (8 E I) for small
// deflection (Euler-Bernoulli; shear adds q L^2 / (2 kappa G A), 1e-6 of it here), within 3 %,
// once the damped rod has come to rest.
TEST(Rods, CantileverTipDeflectionIsEulerBernoullis) {
  const RodMaterial material = stiffRod();
  const double length = 1.0;
  const double area = kPi * material.radius * material.radius;
  const double q = material.density * area * 9.81;
  const double area_moment = kPi * std::pow(material.radius, 4) / 4.0;
  const double expected = q * std::pow(length, 4) / (8.0 * material.young_modulus * area_moment);
  for (int segments : {20, 40}) {
    double first = 0.0;
    for (int substeps : {5, 20}) {
      Rod rod = clampedRod(length, segments, material);
      settle(rod, 240, substeps, 20.0);
      const double deflection = 1.0 - rod.position.back().z();
      std::printf(
          "%d segments: tip deflection %.6f m, Euler-Bernoulli %.6f m (%.2f %%), tip speed "
          "%.3g m/s\n",
          segments, deflection, expected, 100.0 * (deflection - expected) / expected,
          rod.velocity.back().norm());
      EXPECT_NEAR(deflection, expected, 0.03 * expected) << segments << " segments";
      // XPBD: the material, not the substep count, sets the stiffness.
      if (substeps == 5) first = deflection;
      EXPECT_NEAR(deflection, first, 0.005 * first) << segments << " segments, " << substeps;
    }
  }
}

// The elastica of a cantilever under its own weight (q per length, clamped at s = 0, free at
// s = L): EI phi'(s) = M(s) = q int_s^L (x(t) - x(s)) dt, so phi'' = -(q / EI) (L - s) cos phi,
// phi(0) = 0, phi'(L) = 0 (phi the slope below the horizontal). Shot on phi'(0) by bisection,
// RK4 in s; returns the tip's drop int_0^L sin phi ds.
double elasticaTipDrop(double q, double bend_stiffness, double length) {
  const int steps = 4000;
  const double ds = length / steps;
  auto shoot = [&](double curvature0, double& drop) {
    double phi = 0.0, dphi = curvature0;
    drop = 0.0;
    auto f = [&](double s, double p) { return -(q / bend_stiffness) * (length - s) * std::cos(p); };
    for (int k = 0; k < steps; ++k) {
      const double s = k * ds;
      // RK4 on (phi, phi'), with the drop integrated alongside (sin phi).
      const double k1p = dphi, k1d = f(s, phi);
      const double k2p = dphi + 0.5 * ds * k1d, k2d = f(s + 0.5 * ds, phi + 0.5 * ds * k1p);
      const double k3p = dphi + 0.5 * ds * k2d, k3d = f(s + 0.5 * ds, phi + 0.5 * ds * k2p);
      const double k4p = dphi + ds * k3d, k4d = f(s + ds, phi + ds * k3p);
      drop += ds / 6.0 *
              (std::sin(phi) + 4.0 * std::sin(phi + 0.5 * ds * (k1p + k2p) / 2.0) +
               std::sin(phi + ds * (k1p + 2.0 * k2p + 2.0 * k3p + k4p) / 6.0));
      phi += ds / 6.0 * (k1p + 2.0 * k2p + 2.0 * k3p + k4p);
      dphi += ds / 6.0 * (k1d + 2.0 * k2d + 2.0 * k3d + k4d);
    }
    return dphi;  // phi'(L), zero for the right start
  };
  double low = 0.0, high = q * length * length / bend_stiffness;  // the linear root curvature
  double drop = 0.0;
  for (int k = 0; k < 100; ++k) {
    const double middle = 0.5 * (low + high);
    (shoot(middle, drop) > 0.0 ? high : low) = middle;
  }
  shoot(0.5 * (low + high), drop);
  return drop;
}

// The same cantilever, soft enough to droop: q L^3 / (EI) = 12.6 (linear theory would put the tip
// 1.57 m below a 1 m rod); the tip's drop against the elastica within 3 %.
TEST(Rods, DroopingCantileverFollowsTheElastica) {
  RodMaterial material = stiffRod();
  material.young_modulus = 1.25e8;
  material.shear_modulus = 1.25e8 / 2.6;
  material.stretch_compliance = 0.0;  // inextensible, as the elastica
  const double length = 1.0;
  const double q = material.density * kPi * material.radius * material.radius * 9.81;
  const double bend_stiffness = material.young_modulus * kPi * std::pow(material.radius, 4) / 4.0;
  const double expected = elasticaTipDrop(q, bend_stiffness, length);
  Rod rod = clampedRod(length, 40, material);
  settle(rod, 600, 10, 10.0);
  const double drop = 1.0 - rod.position.back().z();
  std::printf(
      "q L^3 / EI = %.3g: tip drop %.5f m, elastica %.5f m (%.2f %%), linear theory %.4f m; "
      "tip speed %.3g m/s\n",
      q / bend_stiffness, drop, expected, 100.0 * (drop - expected) / expected,
      q / (8.0 * bend_stiffness), rod.velocity.back().norm());
  EXPECT_NEAR(drop, expected, 0.03 * expected);
  EXPECT_LT(rod.velocity.back().norm(), 1e-3);
}

// A rod clamped at both ends (the middles of its first and last segments, L = 1 m apart), the
// far clamp turned by theta about the rod's axis: at rest every joint carries the twisting moment
// G J theta / L within 3 % (the twist spread evenly along it), and no bending moment.
TEST(Rods, TwistedRodCarriesGJThetaOverL) {
  RodMaterial material = stiffRod();
  material.young_modulus = 1e7;  // a soft cable: E = 10 MPa, G = E / 2.6
  material.shear_modulus = 1e7 / 2.6;
  const double length = 1.0, theta = 1.0;
  const int segments = 21;
  const double l = length / (segments - 1);
  Rod rod = makeStraightRod(Vec3(-0.5 * l, 0.0, 1.0), Vec3(length + 0.5 * l, 0.0, 1.0), segments,
                            material);
  rod.fixParticle(0);
  rod.fixSegment(0);
  rod.fixParticle(segments);
  rod.fixSegment(segments - 1);
  const Vec3 axis = Vec3::UnitX();
  rod.orientation.back() =
      (Quaternion(Eigen::AngleAxisd(theta, axis)) * rod.orientation.back()).normalized();
  settle(rod, 240, 10, 20.0, Vec3::Zero());
  const double polar_moment = kPi * std::pow(material.radius, 4) / 2.0;
  const double expected = material.shear_modulus * polar_moment * theta / length;
  double smallest = 1e300, largest = 0.0, most_bending = 0.0;
  for (int k = 0; k + 1 < rod.segments(); ++k) {
    const Vec3 moment = rodJointMoment(rod, k);
    smallest = std::min(smallest, moment.z());
    largest = std::max(largest, moment.z());
    most_bending = std::max(most_bending, moment.head<2>().norm());
  }
  std::printf(
      "twisted by %.2f rad: joint twisting moments %.6g .. %.6g N m, G J theta / L = %.6g "
      "N m; largest bending moment %.3g N m\n",
      theta, smallest, largest, expected, most_bending);
  EXPECT_NEAR(smallest, expected, 0.03 * expected);
  EXPECT_NEAR(largest, expected, 0.03 * expected);
  EXPECT_LT(most_bending, 0.01 * expected);
}

}  // namespace
}  // namespace pbd_cloth

namespace pbd_cloth {
namespace {

// A soft cable (50 segments, E = 10 MPa) held by one end, let fall from horizontal and swing for
// 3 s undamped at 60 Hz x 10 substeps: it stays finite and its energy (gravity and translation)
// never grows past its start by more than 1 % of m g L: the solve adds no energy. Its segments
// stretch under the whip of the fall by the material's own compliance (measured 0.44 %: about
// 3.4 N on EA = 785 N, four times the cable's weight); made inextensible (stretch_compliance 0)
// the same cable keeps every length within 1e-4 (measured 6.7e-6): what remains is the solve's.
TEST(Rods, SwingingCableStaysWholeAndGainsNoEnergy) {
  for (double stretch_compliance : {-1.0, 0.0}) {
    RodMaterial material;
    material.radius = 0.005;
    material.young_modulus = 1e7;
    material.shear_modulus = 1e7 / 2.6;
    material.stretch_compliance = stretch_compliance;
    Rod rod = makeStraightRod(Vec3(0.0, 0.0, 1.0), Vec3(1.0, 0.0, 1.0), 50, material);
    rod.fixParticle(0);
    rod.fixSegment(0);
    RodStepSettings settings;
    settings.substeps = 10;
    RodSolver solver;
    solver.prepare(rod.segments());
    auto energy = [&rod]() {
      double e = 0.0;
      for (int i = 0; i < rod.size(); ++i) {
        e += rod.mass[i] * (9.81 * rod.position[i].z() + 0.5 * rod.velocity[i].squaredNorm());
      }
      return e;
    };
    double mass = 0.0;
    for (double m : rod.mass) mass += m;
    const double start = energy(), scale = mass * 9.81 * 1.0;
    double most = start, worst_stretch = 0.0, lowest_tip = 1.0;
    for (int k = 0; k < 180; ++k) {
      stepRod(rod, 1.0 / 60.0, settings, solver);
      most = std::max(most, energy());
      lowest_tip = std::min(lowest_tip, rod.position.back().z());
      for (int s = 0; s < rod.segments(); ++s) {
        const double stretch =
            std::abs((rod.position[s + 1] - rod.position[s]).norm() / rod.rest_length[s] - 1.0);
        worst_stretch = std::max(worst_stretch, stretch);
      }
    }
    std::printf(
        "swinging cable, stretch_compliance %g: largest stretch %.3g, energy at most %.4f "
        "J (start %.4f J), tip down to z = %.3f m\n",
        stretch_compliance, worst_stretch, most, start, lowest_tip);
    ASSERT_TRUE(std::isfinite(rod.position.back().norm()));
    EXPECT_LT(worst_stretch, stretch_compliance == 0.0 ? 1e-4 : 0.01);
    EXPECT_LT(most, start + 0.01 * scale);
    EXPECT_LT(lowest_tip, 0.2);  // it swung down (a 1 m cable hung from z = 1)
  }
}

}  // namespace
}  // namespace pbd_cloth
