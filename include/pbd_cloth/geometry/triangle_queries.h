// Closest-point queries on triangles and segments (Ericson 2005, Real-Time Collision Detection,
// sec. 5.1.5 and 5.1.9). The Voronoi-region search of a point among a triangle's corners, edges
// and face is written once (triangleRegion); its two evaluations keep the arithmetic their callers
// had, so that results stay the same to the bit: the closest point itself (the mesh shape's
// distance, mesh_shape.cpp) and the distance computed from the vector from the point (the
// self-collision candidates' cull, self_collision.cpp).
#pragma once

#include <algorithm>

#include "pbd_cloth/geometry/vector_types.h"

namespace pbd_cloth {

// Which feature of a triangle holds the closest point: its face, edge k (v_k, v_{k+1}) or vertex k.
enum class TriangleFeature { kFace, kEdge, kVertex };

// The region of p and the dot products that locate it. Only those the search reached are set
// (the rest stay zero): bp, d3 and d4 from the second corner test on, cp, d5 and d6 from the
// third, va for the face.
struct TriangleRegion {
  TriangleFeature feature = TriangleFeature::kFace;
  int index = 0;  // vertex k or edge k (v_k, v_{k+1}); 0 for the face
  Vec3 ab, ac, ap, bp = Vec3::Zero(), cp = Vec3::Zero();
  double d1 = 0.0, d2 = 0.0, d3 = 0.0, d4 = 0.0, d5 = 0.0, d6 = 0.0;
  double va = 0.0, vb = 0.0, vc = 0.0;
};

// The Voronoi region of p among the corners, edges and face of triangle (a, b, c) (Ericson 2005,
// sec. 5.1.5: the vertices first, then the edges, then the face).
inline TriangleRegion triangleRegion(const Vec3& p, const Vec3& a, const Vec3& b, const Vec3& c) {
  TriangleRegion r;
  r.ab = b - a;
  r.ac = c - a;
  r.ap = p - a;
  r.d1 = r.ab.dot(r.ap);
  r.d2 = r.ac.dot(r.ap);
  if (r.d1 <= 0.0 && r.d2 <= 0.0) {
    r.feature = TriangleFeature::kVertex;
    r.index = 0;
    return r;
  }
  r.bp = p - b;
  r.d3 = r.ab.dot(r.bp);
  r.d4 = r.ac.dot(r.bp);
  if (r.d3 >= 0.0 && r.d4 <= r.d3) {
    r.feature = TriangleFeature::kVertex;
    r.index = 1;
    return r;
  }
  r.vc = r.d1 * r.d4 - r.d3 * r.d2;
  if (r.vc <= 0.0 && r.d1 >= 0.0 && r.d3 <= 0.0) {
    r.feature = TriangleFeature::kEdge;
    r.index = 0;
    return r;
  }
  r.cp = p - c;
  r.d5 = r.ab.dot(r.cp);
  r.d6 = r.ac.dot(r.cp);
  if (r.d6 >= 0.0 && r.d5 <= r.d6) {
    r.feature = TriangleFeature::kVertex;
    r.index = 2;
    return r;
  }
  r.vb = r.d5 * r.d2 - r.d1 * r.d6;
  if (r.vb <= 0.0 && r.d2 >= 0.0 && r.d6 <= 0.0) {
    r.feature = TriangleFeature::kEdge;
    r.index = 2;  // edge (c, a)
    return r;
  }
  r.va = r.d3 * r.d6 - r.d5 * r.d4;
  if (r.va <= 0.0 && (r.d4 - r.d3) >= 0.0 && (r.d5 - r.d6) >= 0.0) {
    r.feature = TriangleFeature::kEdge;
    r.index = 1;  // edge (b, c)
    return r;
  }
  r.feature = TriangleFeature::kFace;
  r.index = 0;
  return r;
}

// Closest point on triangle (a, b, c) to p, and the feature it lies on. A degenerate triangle
// whose p falls in no corner or edge region gives a non-finite point.
inline Vec3 closestPointOnTriangle(const Vec3& p, const Vec3& a, const Vec3& b, const Vec3& c,
                                   TriangleFeature& feature, int& index) {
  const TriangleRegion r = triangleRegion(p, a, b, c);
  feature = r.feature;
  index = r.index;
  if (r.feature == TriangleFeature::kVertex) return r.index == 0 ? a : r.index == 1 ? b : c;
  if (r.feature == TriangleFeature::kEdge) {
    if (r.index == 0) return a + (r.d1 / (r.d1 - r.d3)) * r.ab;
    if (r.index == 2) return a + (r.d2 / (r.d2 - r.d6)) * r.ac;
    return b + ((r.d4 - r.d3) / ((r.d4 - r.d3) + (r.d5 - r.d6))) * (c - b);
  }
  const double denominator = 1.0 / (r.va + r.vb + r.vc);
  return a + r.ab * (r.vb * denominator) + r.ac * (r.vc * denominator);
}

// Distance from q to the closest point of the triangle (p1, p2, p3), from the vector q - p1 (or
// q - p2, q - p3) so that it does not cancel far from the origin. A degenerate triangle whose q
// falls in its face region gives 0 (a cull that culls nothing).
inline double pointTriangleDistance(const Vec3& q, const Vec3& p1, const Vec3& p2, const Vec3& p3) {
  const TriangleRegion r = triangleRegion(q, p1, p2, p3);
  if (r.feature == TriangleFeature::kVertex) {
    return r.index == 0 ? r.ap.norm() : r.index == 1 ? r.bp.norm() : r.cp.norm();
  }
  if (r.feature == TriangleFeature::kEdge) {
    if (r.index == 0) return (r.ap - (r.d1 / (r.d1 - r.d3)) * r.ab).norm();
    if (r.index == 2) return (r.ap - (r.d2 / (r.d2 - r.d6)) * r.ac).norm();
    return (r.bp - ((r.d4 - r.d3) / ((r.d4 - r.d3) + (r.d5 - r.d6))) * (p3 - p2)).norm();
  }
  const double denominator = r.va + r.vb + r.vc;
  if (!(denominator > 0.0)) return 0.0;  // degenerate: no cull
  return (r.ap - (r.vb / denominator) * r.ab - (r.vc / denominator) * r.ac).norm();
}

// Distance between the segments p1p2 and q1q2 (Ericson 2005, sec. 5.1.9: the closest points of
// the lines, clamped to the segments in turn). A segment shorter than 1e-8 m counts as a point.
inline double segmentSegmentDistance(const Vec3& p1, const Vec3& p2, const Vec3& q1,
                                     const Vec3& q2) {
  constexpr double kDegenerate = 1e-16;  // squared length (m^2)
  const Vec3 d1 = p2 - p1, d2 = q2 - q1, r = p1 - q1;
  const double a = d1.squaredNorm(), e = d2.squaredNorm(), f = d2.dot(r);
  double s = 0.0, t = 0.0;
  if (a <= kDegenerate && e <= kDegenerate) return r.norm();
  if (a <= kDegenerate) {
    t = std::clamp(f / e, 0.0, 1.0);
  } else {
    const double c = d1.dot(r);
    if (e <= kDegenerate) {
      s = std::clamp(-c / a, 0.0, 1.0);
    } else {
      const double b = d1.dot(d2), denominator = a * e - b * b;
      s = denominator > 0.0 ? std::clamp((b * f - c * e) / denominator, 0.0, 1.0) : 0.0;
      t = (b * s + f) / e;
      if (t < 0.0) {
        t = 0.0;
        s = std::clamp(-c / a, 0.0, 1.0);
      } else if (t > 1.0) {
        t = 1.0;
        s = std::clamp((b - c) / a, 0.0, 1.0);
      }
    }
  }
  return (p1 + s * d1 - (q1 + t * d2)).norm();
}

}  // namespace pbd_cloth
