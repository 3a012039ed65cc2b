#include "pbd_cloth/geometry/shapes.h"

#include <algorithm>
#include <cmath>
#include <limits>

namespace pbd_cloth {

namespace {

// Sphere tracing stops this close to contact (relative to the swept radius) ...
constexpr double kSweepTolerance = 1e-7;
// ... or after this many steps: only a path grazing the surface at a tiny angle needs more, and
// such a path penetrates by no more than the discrete test then resolves.
constexpr int kSweepMaxSteps = 64;

// Nearest t > 0 among the roots of a t^2 + 2 b t + c = 0 that `accept` (kNoRayHit if none).
template <typename Accept>
double nearestRoot(double a, double b, double c, Accept accept) {
  if (a <= 0.0) return kNoRayHit;
  const double discriminant = b * b - a * c;
  if (discriminant < 0.0) return kNoRayHit;
  const double root = std::sqrt(discriminant);
  const double t0 = (-b - root) / a;
  if (t0 > 0.0 && accept(t0)) return t0;
  const double t1 = (-b + root) / a;
  if (t1 > 0.0 && accept(t1)) return t1;
  return kNoRayHit;
}

// The side wall x^2 + y^2 = r^2 for |z| <= h (no ends).
double rayTube(const Vec3& o, const Vec3& d, double radius, double half_length) {
  return nearestRoot(d.x() * d.x() + d.y() * d.y(), o.x() * d.x() + o.y() * d.y(),
                     o.x() * o.x() + o.y() * o.y() - radius * radius,
                     [&](double t) { return std::abs(o.z() + t * d.z()) <= half_length; });
}

// The flat ends z = +-h within radius r.
double rayDiscs(const Vec3& o, const Vec3& d, double radius, double half_length) {
  if (d.z() == 0.0) return kNoRayHit;
  double best = kNoRayHit;
  for (double z : {-half_length, half_length}) {
    const double t = (z - o.z()) / d.z();
    const double x = o.x() + t * d.x(), y = o.y() + t * d.y();
    if (t > 0.0 && x * x + y * y <= radius * radius) best = std::min(best, t);
  }
  return best;
}

// Slabs (Kay and Kajiya 1986): the entry point, or the exit point from inside.
double rayBox(const Vec3& o, const Vec3& d, const Vec3& half) {
  double t_near = -kNoRayHit, t_far = kNoRayHit;
  for (int i = 0; i < 3; ++i) {
    if (d[i] == 0.0) {
      if (std::abs(o[i]) > half[i]) return kNoRayHit;
      continue;
    }
    double t0 = (-half[i] - o[i]) / d[i];
    double t1 = (half[i] - o[i]) / d[i];
    if (t0 > t1) std::swap(t0, t1);
    t_near = std::max(t_near, t0);
    t_far = std::min(t_far, t1);
  }
  if (t_near > t_far || t_far <= 0.0) return kNoRayHit;
  return t_near > 0.0 ? t_near : t_far;
}

double rayPlane(const Vec3& o, const Vec3& d, const Vec3& normal, double offset) {
  const double rate = normal.dot(d);
  if (rate == 0.0) return kNoRayHit;
  const double t = (offset - normal.dot(o)) / rate;
  return t > 0.0 ? t : kNoRayHit;
}

}  // namespace

double raySphere(const Vec3& o, const Vec3& d, const Vec3& centre, double radius) {
  const Vec3 oc = o - centre;
  return nearestRoot(d.dot(d), oc.dot(d), oc.dot(oc) - radius * radius,
                     [](double) { return true; });
}

double rayHit(const Shape& shape, const Vec3& o, const Vec3& d) {
  switch (shape.type) {
    case ShapeType::kSphere:
      return raySphere(o, d, Vec3::Zero(), shape.radius);
    case ShapeType::kBox:
      return rayBox(o, d, shape.half_extents);
    case ShapeType::kCapsule: {
      const Vec3 end(0.0, 0.0, shape.half_length);
      return std::min({rayTube(o, d, shape.radius, shape.half_length),
                       raySphere(o, d, end, shape.radius), raySphere(o, d, -end, shape.radius)});
    }
    case ShapeType::kCylinder:
      return std::min(rayTube(o, d, shape.radius, shape.half_length),
                      rayDiscs(o, d, shape.radius, shape.half_length));
    case ShapeType::kPlane:
      return rayPlane(o, d, shape.normal, shape.offset);
    case ShapeType::kMesh:
      break;
  }
  return kNoRayHit;
}

void worldBounds(const Shape& shape, const Frame& frame, Vec3& lo, Vec3& hi) {
  Vec3 extent = Vec3::Zero();
  switch (shape.type) {
    case ShapeType::kPlane: {
      const double inf = std::numeric_limits<double>::infinity();
      lo = Vec3::Constant(-inf);
      hi = Vec3::Constant(inf);
      // The solid is n . x <= level in world coordinates (signedDistance: n_local . x_local <=
      // offset, x_local = R^T (x - t)). With n along axis a alone it is x_a <= level / n_a (or >=
      // for n_a < 0): a floor bounds z from above, so the obstacles' cull skips it for a cloth
      // far above it. Any other normal leaves the half-space unbounded on every axis.
      const Vec3 n = frame.rotation * shape.normal;
      const double level = shape.offset + n.dot(frame.translation);
      for (int a = 0; a < 3; ++a) {
        if (n[(a + 1) % 3] != 0.0 || n[(a + 2) % 3] != 0.0 || n[a] == 0.0) continue;
        // Grown by a relative 1e-12 and the padding, so rounding never cuts off a contact.
        const double end = level / n[a];
        const double margin = 1e-12 * (1.0 + std::abs(end)) + std::abs(shape.padding);
        if (n[a] > 0.0) {
          hi[a] = end + margin;
        } else {
          lo[a] = end - margin;
        }
      }
      return;
    }
    case ShapeType::kSphere:
      extent = Vec3::Constant(shape.radius);
      break;
    case ShapeType::kCapsule:
      extent = shape.half_length * frame.rotation.col(2).cwiseAbs() + Vec3::Constant(shape.radius);
      break;
    case ShapeType::kBox:
      extent = frame.rotation.cwiseAbs() * shape.half_extents;
      break;
    case ShapeType::kCylinder:
      extent = frame.rotation.cwiseAbs() * Vec3(shape.radius, shape.radius, shape.half_length);
      break;
    case ShapeType::kMesh: {
      // The local box of the mesh, rotated: its centre moves, its half extents grow by |R|.
      const Vec3 centre = 0.5 * (shape.mesh->boundsMax() + shape.mesh->boundsMin());
      const Vec3 half = 0.5 * (shape.mesh->boundsMax() - shape.mesh->boundsMin());
      const Vec3 middle = frame.toWorld(centre);
      extent = frame.rotation.cwiseAbs() * half + Vec3::Constant(shape.padding);
      lo = middle - extent;
      hi = middle + extent;
      return;
    }
  }
  extent.array() += shape.padding;
  lo = frame.translation - extent;
  hi = frame.translation + extent;
}

namespace {

// Distance to a cylinder of radius r about z with flat ends at z = +-h: the 2D box distance in
// (radial distance, |z|), exact inside and outside.
double cylinderDistance(double r, double h, const Vec3& x, Vec3& normal) {
  const double rho = std::hypot(x.x(), x.y());
  const Vec3 radial = rho > 0.0 ? Vec3(x.x() / rho, x.y() / rho, 0.0) : Vec3::UnitX();
  const Vec3 axial(0.0, 0.0, x.z() < 0.0 ? -1.0 : 1.0);
  const double dr = rho - r;
  const double dz = std::abs(x.z()) - h;
  if (dr > 0.0 && dz > 0.0) {  // beyond the rim
    const double distance = std::hypot(dr, dz);
    normal = (dr * radial + dz * axial) / distance;
    return distance;
  }
  if (dr > 0.0 || dz > 0.0 || dr > dz) {
    // Outside the side or an end, or inside and nearer the side than an end.
    const bool side = dr > dz;
    normal = side ? radial : axial;
    return side ? dr : dz;
  }
  normal = axial;
  return dz;
}

double unpaddedDistance(const Shape& shape, const Vec3& x, Vec3& normal, int* hint) {
  switch (shape.type) {
    case ShapeType::kPlane:
      normal = shape.normal;
      return shape.normal.dot(x) - shape.offset;
    case ShapeType::kSphere: {
      const double length = x.norm();
      // At the centre every direction is equally short: pick +z.
      normal = length > 0.0 ? Vec3(x / length) : Vec3::UnitZ();
      return length - shape.radius;
    }
    case ShapeType::kCapsule: {
      const Vec3 axis_point(0.0, 0.0, std::clamp(x.z(), -shape.half_length, shape.half_length));
      const Vec3 away = x - axis_point;
      const double length = away.norm();
      normal = length > 0.0 ? Vec3(away / length) : Vec3::UnitX();
      return length - shape.radius;
    }
    case ShapeType::kBox: {
      const Vec3 q = x.cwiseAbs() - shape.half_extents;
      const Vec3 sign(x.x() < 0.0 ? -1.0 : 1.0, x.y() < 0.0 ? -1.0 : 1.0, x.z() < 0.0 ? -1.0 : 1.0);
      int axis = 0;
      const double largest = q.maxCoeff(&axis);
      if (largest > 0.0) {
        // Outside: distance to the nearest face, edge or corner.
        const Vec3 outside = q.cwiseMax(0.0);
        const double distance = outside.norm();
        normal = outside.cwiseProduct(sign) / distance;
        return distance;
      }
      // Inside: out through the nearest face.
      normal = Vec3::Zero();
      normal[axis] = sign[axis];
      return largest;
    }
    case ShapeType::kCylinder:
      return cylinderDistance(shape.radius, shape.half_length, x, normal);
    case ShapeType::kMesh:
      return shape.mesh->signedDistance(x, normal, hint);
  }
  normal = Vec3::UnitZ();
  return 0.0;
}

}  // namespace

double signedDistance(const Shape& shape, const Vec3& x, Vec3& normal, int* hint) {
  return unpaddedDistance(shape, x, normal, hint) - shape.padding;
}

double signedDistance(const Shape& shape, const Vec3& x) {
  Vec3 unused;
  return signedDistance(shape, x, unused);
}

bool surelyFartherThan(const Shape& shape, const Vec3& x, double reach) {
  // Rounding in signedDistance and the caller's subtraction is a few units in the last place of
  // the lengths involved; 1e-9 of the squares is far more, and far less than any gap that matters.
  constexpr double kMargin = 1.0 + 1e-9;
  // A coordinate at a time: the caller has just stored x so, and a 16-byte load of it would wait.
  const double x0 = x.x(), x1 = x.y(), x2 = x.z();
  double far = reach + shape.padding;
  double d2 = 0.0;
  double squared = 0.0;
  switch (shape.type) {
    case ShapeType::kSphere:
      far += shape.radius;
      squared = x0 * x0 + x1 * x1 + x2 * x2;
      break;
    case ShapeType::kCapsule:
      far += shape.radius;
      d2 = x2 - std::clamp(x2, -shape.half_length, shape.half_length);
      squared = x0 * x0 + x1 * x1 + d2 * d2;
      break;
    case ShapeType::kBox: {
      const double q0 = std::max(std::abs(x0) - shape.half_extents.x(), 0.0);
      const double q1 = std::max(std::abs(x1) - shape.half_extents.y(), 0.0);
      const double q2 = std::max(std::abs(x2) - shape.half_extents.z(), 0.0);
      squared = q0 * q0 + q1 * q1 + q2 * q2;
      break;
    }
    case ShapeType::kPlane:
    case ShapeType::kCylinder:
    case ShapeType::kMesh:
      return false;
  }
  return far > 0.0 && squared > kMargin * far * far;
}

double boundingRadius(const Shape& shape) {
  double radius = std::numeric_limits<double>::infinity();
  switch (shape.type) {
    case ShapeType::kSphere:
      radius = shape.radius;
      break;
    case ShapeType::kCapsule:
      radius = shape.radius + shape.half_length;
      break;
    case ShapeType::kBox:
      radius = shape.half_extents.norm();
      break;
    case ShapeType::kCylinder:
      radius = std::hypot(shape.radius, shape.half_length);
      break;
    case ShapeType::kMesh:
      radius =
          shape.mesh->boundsMin().cwiseAbs().cwiseMax(shape.mesh->boundsMax().cwiseAbs()).norm();
      break;
    case ShapeType::kPlane:
      return radius;
  }
  return radius + std::max(shape.padding, 0.0);
}

bool sweepSphere(const Shape& shape, const Vec3& a, const Vec3& b, double r, double start_distance,
                 const Vec3& start_normal, double& t, Vec3& normal, int* hint) {
  const Vec3 direction = b - a;
  const double length = direction.norm();
  const double tolerance = kSweepTolerance * r;
  t = 0.0;
  double clearance = start_distance - r;
  normal = start_normal;
  for (int step = 0; step < kSweepMaxSteps; ++step) {
    if (clearance <= tolerance) return true;
    if (length == 0.0) return false;
    t += clearance / length;
    if (t > 1.0) return false;
    clearance = signedDistance(shape, a + t * direction, normal, hint) - r;
  }
  return false;
}

}  // namespace pbd_cloth
