// A Cosserat rod's state and its construction (model/rod.h).
#include "pbd_cloth/model/rod.h"

#include <cmath>
#include <limits>

namespace pbd_cloth {

namespace {
constexpr double kPi = 3.14159265358979323846;
}

RodStiffness rodStiffness(const RodMaterial& m) {
  RodStiffness k;
  const double area = kPi * m.radius * m.radius;
  const double area_moment = kPi * std::pow(m.radius, 4) / 4.0;  // I, about a diameter
  if (m.stretch_compliance < 0.0) {
    k.stretch = m.young_modulus * area;
    k.shear = m.shear_modulus * area;
  } else {
    const double infinite = std::numeric_limits<double>::infinity();
    k.stretch = k.shear = m.stretch_compliance > 0.0 ? 1.0 / m.stretch_compliance : infinite;
  }
  k.bend = m.young_modulus * area_moment;
  k.twist = m.shear_modulus * 2.0 * area_moment;  // J = 2 I for a circle
  return k;
}

void Rod::fixParticle(int i) {
  inverse_mass[i] = 0.0;
  velocity[i].setZero();
}

void Rod::fixSegment(int i) {
  inverse_inertia_bend[i] = inverse_inertia_twist[i] = 0.0;
  angular_velocity[i].setZero();
}

Rod makeRod(const Vec3Array& points, const RodMaterial& material) {
  Rod rod;
  const int n = static_cast<int>(points.size());
  const int segments = n - 1;
  const double area = kPi * material.radius * material.radius;
  const double r2 = material.radius * material.radius;
  rod.position = points;
  rod.velocity.assign(n, Vec3::Zero());
  rod.substep_start = rod.position;
  rod.mass.assign(n, 0.0);
  rod.rest_length.resize(segments);
  rod.orientation.resize(segments);
  rod.inverse_inertia_bend.resize(segments);
  rod.inverse_inertia_twist.resize(segments);
  for (int s = 0; s < segments; ++s) {
    const Vec3 along = points[s + 1] - points[s];
    const double length = along.norm();
    const double segment_mass = material.density * area * length;
    rod.rest_length[s] = length;
    rod.mass[s] += 0.5 * segment_mass;
    rod.mass[s + 1] += 0.5 * segment_mass;
    // A solid cylinder of the segment's length: m (3 r^2 + l^2) / 12 about a diameter through its
    // middle, m r^2 / 2 about its axis.
    rod.inverse_inertia_bend[s] = 12.0 / (segment_mass * (3.0 * r2 + length * length));
    rod.inverse_inertia_twist[s] = 2.0 / (segment_mass * r2);
    const Vec3 tangent = along / length;
    if (s == 0) {
      rod.orientation[s] = Quaternion::FromTwoVectors(Vec3::UnitZ(), tangent).normalized();
    } else {
      const Vec3 previous = rod.orientation[s - 1] * Vec3::UnitZ();
      rod.orientation[s] =
          (Quaternion::FromTwoVectors(previous, tangent) * rod.orientation[s - 1]).normalized();
    }
  }
  rod.inverse_mass.resize(n);
  for (int i = 0; i < n; ++i) rod.inverse_mass[i] = 1.0 / rod.mass[i];
  rod.orientation_start = rod.orientation;
  rod.angular_velocity.assign(segments, Vec3::Zero());
  rod.rest_darboux.assign(segments > 0 ? segments - 1 : 0, Vec3::Zero());
  rod.stretch_shear_lambda.assign(segments, Vec3::Zero());
  rod.bend_twist_lambda.assign(rod.rest_darboux.size(), Vec3::Zero());
  rod.stiffness = rodStiffness(material);
  rod.radius = material.radius;
  return rod;
}

Rod makeStraightRod(const Vec3& start, const Vec3& end, int segments, const RodMaterial& material) {
  Vec3Array points(segments + 1);
  for (int i = 0; i <= segments; ++i) {
    points[i] = start + (end - start) * (static_cast<double>(i) / segments);
  }
  return makeRod(points, material);
}

void applySmallRotation(Quaternion& q, const Vec3& rotation) {
  const Quaternion dq(0.0, 0.5 * rotation.x(), 0.5 * rotation.y(), 0.5 * rotation.z());
  q.coeffs() += (dq * q).coeffs();
  q.normalize();
}

Vec3 darbouxVector(const Rod& rod, int k) {
  Quaternion relative = rod.orientation[k].conjugate() * rod.orientation[k + 1];
  if (relative.w() < 0.0) relative.coeffs() = -relative.coeffs();  // the shorter rotation
  const double mean_length = 0.5 * (rod.rest_length[k] + rod.rest_length[k + 1]);
  return (2.0 / mean_length) * relative.vec();
}

}  // namespace pbd_cloth
