// Geometry of the obstacles and robot links: the one shape interface, used alike by the
// collisions, the robot links and the depth camera. In the shape's own frame: the signed distance
// of a point to a plane, sphere, box, capsule, cylinder or closed triangle mesh, the closest
// surface point, a ray's first hit and the bounds, and a swept-sphere query for continuous
// collision handling, which works for every shape because every distance here is exact
// (1-Lipschitz). Plain structs and a switch on the shape type: no virtual calls in the contact
// loop.
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>

#include <limits>
#include <memory>

#include "pbd_cloth/geometry/mesh_shape.h"
#include "pbd_cloth/geometry/pose.h"
#include "pbd_cloth/geometry/shape_type.h"
#include "pbd_cloth/geometry/vector_types.h"

namespace pbd_cloth {

// An obstacle in its own frame. Sphere: centre at the origin. Capsule: the segment from
// (0,0,-half_length) to (0,0,half_length) inflated by radius (local z axis, like rviz's cylinder).
// Box: centred at the origin with these half edge lengths. Plane: normal.x = offset with a unit
// normal; the free side is normal.x - offset >= 0 (the seed's C(p) = n^T p - d_rest >= 0).
// Cylinder: radius about the local z axis, flat ends at z = +-half_length (URDF's cylinder). Mesh:
// the triangle mesh in its own (already scaled) coordinates. Every shape is grown by `padding`.
struct Shape {
  ShapeType type = ShapeType::kSphere;
  double radius = 0.0;
  double half_length = 0.0;
  Vec3 half_extents = Vec3::Zero();
  Vec3 normal = Vec3::UnitZ();
  double offset = 0.0;
  std::shared_ptr<const TriangleMesh> mesh;
  double padding = 0.0;
};

// World-space bounding box of the shape placed at `frame`. A plane's solid is a half-space:
// infinite, except on the axis its normal lies along when the normal lies exactly along one
// (a floor, a wall), where it ends at the plane.
void worldBounds(const Shape& shape, const Frame& frame, Vec3& lo, Vec3& hi);

// Signed distance of the local point x to the surface (negative inside) and the outward unit
// normal of the nearest surface point (inside: the direction of the shortest way out). The distance
// is exact for every shape (the mesh's by closest-triangle search), hence 1-Lipschitz, which
// sweepSphere relies on; padding subtracts a constant and keeps that.
// `hint`: the mesh's search hint (TriangleMesh::signedDistance), kept per particle by the caller;
// other shapes ignore it.
double signedDistance(const Shape& shape, const Vec3& x, Vec3& normal, int* hint = nullptr);
double signedDistance(const Shape& shape, const Vec3& x);

// The point of the (padded) surface nearest to the local point x: x moved by its signed distance
// against the normal (exact because the distance is).
inline Vec3 closestPoint(const Shape& shape, const Vec3& x) {
  Vec3 normal;
  const double distance = signedDistance(shape, x, normal);
  return x - distance * normal;
}

// No hit of a ray (rayHit, raySphere).
constexpr double kNoRayHit = std::numeric_limits<double>::infinity();

// The first hit t > 0 of the ray o + t d (local frame, any scale of d) with the shape's unpadded
// surface, in closed form; kNoRayHit when it misses, and for a mesh (the depth camera draws a
// mesh's triangles instead, depth_camera.cpp). From inside a solid shape: where the ray leaves it.
double rayHit(const Shape& shape, const Vec3& o, const Vec3& d);
// The same for a sphere of this radius about `centre` (a particle).
double raySphere(const Vec3& o, const Vec3& d, const Vec3& centre, double radius);

// True when the local point x lies farther than `reach` (>= 0) from the shape's surface, outside
// it, by a margin well beyond rounding (a relative 1e-9): signedDistance(shape, x) - r >= d then
// holds as computed, for any split reach = r + d. Without a square root, a division or a normal:
// what a contact pass tests first for the particles near a shape but clear of it (fabric_table:
// 98 % of the ball's distances only to learn that). For a sphere, a capsule and a box (outside it)
// the squared distance against reach's square; the other shapes answer false, and so does a point
// within the margin: the caller then computes the distance.
bool surelyFartherThan(const Shape& shape, const Vec3& x, double reach);

// The radius of a ball about the shape's origin that holds the shape grown by its padding; +inf for
// a plane. Since the distance to a set is at least the distance to a ball holding it, a point x
// (local frame) has signedDistance(x) >= |x| - boundingRadius: a test without the local frame,
// for a shape that does not move (Collisions::projectObstaclesOn).
double boundingRadius(const Shape& shape);

// Continuous collision: the first fraction t in [0, 1] at which a sphere of radius r moving along
// the segment a -> b (local frame) touches the shape, i.e. signedDistance(a + t (b - a)) <= r.
// Sphere tracing (Hart 1996): a step of (distance - r) never crosses the surface because the
// distance is 1-Lipschitz, so a segment that crosses a thin plate is always caught. Returns false
// when the whole segment stays free (or, for a grazing path, when the march does not converge).
// `start_distance` and `start_normal` are signedDistance at a (the caller has them already); on a
// hit, `normal` is the outward normal at the entry point.
bool sweepSphere(const Shape& shape, const Vec3& a, const Vec3& b, double r, double start_distance,
                 const Vec3& start_normal, double& t, Vec3& normal, int* hint = nullptr);

}  // namespace pbd_cloth
