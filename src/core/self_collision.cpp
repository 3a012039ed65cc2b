#include "pbd_cloth/self_collision.h"

#include <algorithm>
#include <cmath>
#include <cstdlib>

namespace pbd_cloth {

namespace {

// A triangle whose sine of the smallest angle is below ~1e-8 has no usable normal: skipped.
constexpr double kDegenerate = 1e-16;
// The projected point may lie this far (in barycentric units) outside the triangle and still count
// as inside, so a vertex over a shared edge is never missed by both triangles through rounding.
constexpr double kInsideTolerance = 1e-6;

// The vertex q over the triangle's plane: unit normal n = p21 x p31 / |p21 x p31| (seed), signed
// distance (q - p1) . n, and the barycentric coordinates of q's projection onto the plane.
struct TriangleProjection {
  Vec3 normal;
  double distance = 0.0;
  double weight[3] = {0.0, 0.0, 0.0};

  bool inside() const {
    return weight[0] >= -kInsideTolerance && weight[1] >= -kInsideTolerance &&
           weight[2] >= -kInsideTolerance;
  }
};

bool projectOntoTriangle(const Vec3& q, const Vec3& p1, const Vec3& p2, const Vec3& p3,
                         TriangleProjection& out) {
  const Vec3 e1 = p2 - p1, e2 = p3 - p1, v = q - p1;
  const Vec3 cross = e1.cross(e2);
  const double d00 = e1.squaredNorm(), d11 = e2.squaredNorm(), d01 = e1.dot(e2);
  const double area2 = cross.squaredNorm();
  if (!(area2 > kDegenerate * d00 * d11)) return false;  // zero-area (or non-finite) triangle
  out.normal = cross / std::sqrt(area2);
  out.distance = v.dot(out.normal);
  const double d20 = v.dot(e1), d21 = v.dot(e2);
  const double denominator = d00 * d11 - d01 * d01;
  out.weight[1] = (d11 * d20 - d01 * d21) / denominator;
  out.weight[2] = (d00 * d21 - d01 * d20) / denominator;
  out.weight[0] = 1.0 - out.weight[1] - out.weight[2];
  return true;
}

bool boxesOverlap(const Vec3& lo_a, const Vec3& hi_a, const Vec3& lo_b, const Vec3& hi_b) {
  return (lo_a.array() <= hi_b.array()).all() && (lo_b.array() <= hi_a.array()).all();
}

}  // namespace

void SelfCollision::reserve(const Particles& particles, const ClothTopology& topology) {
  hash_.reserve(particles.cloth_count);
  grown_lo_.reserve(particles.cloth_count);
  grown_hi_.reserve(particles.cloth_count);
  pairs_.reserve(4 * static_cast<std::size_t>(topology.triangleCount()));
}

void SelfCollision::findPairs(const Particles& p, const ClothTopology& topology,
                              const Vec3Array& lo, const Vec3Array& hi, double thickness) {
  pairs_.clear();
  const int vertices = p.cloth_count;
  const int triangles = topology.triangleCount();
  if (triangles == 0) return;
  const auto& tri = topology.triangles;
  // Vertex and triangle boxes each grown by h / 2: they overlap when within h of each other.
  const double half = 0.5 * thickness;
  grown_lo_.resize(vertices);
  grown_hi_.resize(vertices);
  double cell = 0.0;
  for (int v = 0; v < vertices; ++v) {
    grown_lo_[v] = lo[v].array() - half;
    grown_hi_[v] = hi[v].array() + half;
    cell = std::max(cell, (grown_hi_[v] - grown_lo_[v]).maxCoeff());
  }
  // A cell about the size of a triangle's box keeps each query to a few cells.
  double triangle_extent = 0.0;
  for (int t = 0; t < triangles; ++t) {
    Vec3 t_lo = grown_lo_[tri[3 * t]], t_hi = grown_hi_[tri[3 * t]];
    for (int k = 1; k < 3; ++k) {
      t_lo = t_lo.cwiseMin(grown_lo_[tri[3 * t + k]]);
      t_hi = t_hi.cwiseMax(grown_hi_[tri[3 * t + k]]);
    }
    triangle_extent += (t_hi - t_lo).maxCoeff();
  }
  cell = std::max(cell, triangle_extent / triangles);
  if (!(cell > 0.0) || !std::isfinite(cell)) return;
  hash_.build(grown_lo_, vertices, cell);

  for (int t = 0; t < triangles; ++t) {
    const int a = static_cast<int>(tri[3 * t]), b = static_cast<int>(tri[3 * t + 1]),
              c = static_cast<int>(tri[3 * t + 2]);
    const Vec3 t_lo = grown_lo_[a].cwiseMin(grown_lo_[b]).cwiseMin(grown_lo_[c]);
    const Vec3 t_hi = grown_hi_[a].cwiseMax(grown_hi_[b]).cwiseMax(grown_hi_[c]);
    const bool triangle_kinematic =
        p.inverse_mass[a] == 0.0 && p.inverse_mass[b] == 0.0 && p.inverse_mass[c] == 0.0;
    const Vec3 query_lo = t_lo.array() - cell;  // a vertex box starts at most one cell lower
    hash_.forEachInRange(query_lo, t_hi, [&](int v) {
      if (v == a || v == b || v == c) return;
      if (triangle_kinematic && p.inverse_mass[v] == 0.0) return;
      if (!boxesOverlap(grown_lo_[v], grown_hi_[v], t_lo, t_hi)) return;
      TriangleProjection start;
      if (!projectOntoTriangle(p.step_start[v], p.step_start[a], p.step_start[b],
                               p.step_start[c], start)) {
        return;
      }
      VertexTrianglePair pair;
      pair.vertex = v;
      pair.triangle[0] = a;
      pair.triangle[1] = b;
      pair.triangle[2] = c;
      pair.side = start.distance >= 0.0 ? 1.0 : -1.0;
      pairs_.push_back(pair);
    });
  }
}

void SelfCollision::preStabilize(Particles& p, double thickness, double max_shift) const {
  for (const VertexTrianglePair& pair : pairs_) {
    const int v = pair.vertex, a = pair.triangle[0], b = pair.triangle[1], c = pair.triangle[2];
    TriangleProjection g;
    if (!projectOntoTriangle(p.position[v], p.position[a], p.position[b], p.position[c], g) ||
        !g.inside()) {
      continue;
    }
    const double violation = pair.side * g.distance - thickness;
    if (violation >= 0.0) continue;
    const double w = p.inverse_mass[v] + g.weight[0] * g.weight[0] * p.inverse_mass[a] +
                     g.weight[1] * g.weight[1] * p.inverse_mass[b] +
                     g.weight[2] * g.weight[2] * p.inverse_mass[c];
    if (w == 0.0) continue;
    const Vec3 step = (std::min(-violation, max_shift) / w * pair.side) * g.normal;
    p.position[v] += p.inverse_mass[v] * step;
    for (int k = 0; k < 3; ++k) {
      p.position[pair.triangle[k]] -= (p.inverse_mass[pair.triangle[k]] * g.weight[k]) * step;
    }
  }
}

void SelfCollision::measureAllowances(const Vec3Array& x, double thickness, double slop) {
  for (VertexTrianglePair& pair : pairs_) {
    pair.allowance = 0.0;
    TriangleProjection g;
    if (projectOntoTriangle(x[pair.vertex], x[pair.triangle[0]], x[pair.triangle[1]],
                            x[pair.triangle[2]], g) &&
        g.inside()) {
      pair.allowance =
          allowanceFor(thickness - std::max(pair.side * g.distance, 0.0), thickness, slop);
    }
  }
}

double SelfCollision::project(Particles& p, double thickness, int substep,
                              const FrictionConfig& friction) {
  double max_change = 0.0;
  for (VertexTrianglePair& pair : pairs_) {
    const int v = pair.vertex;
    const int* t = pair.triangle;
    const double wv = p.inverse_mass[v];
    const double wt[3] = {p.inverse_mass[t[0]], p.inverse_mass[t[1]], p.inverse_mass[t[2]]};
    ContactState& state = pair.state;
    if (!state.current(substep)) {
      state.begin(substep);
      // Beside the triangle the vertex may go round its edge to the other side (a hinge
      // neighbour rotating about the shared edge, a layer sliding past a fold): the side only
      // freezes while the vertex is over the triangle, where changing it means passing through.
      TriangleProjection start;
      if (projectOntoTriangle(p.substep_start[v], p.substep_start[t[0]], p.substep_start[t[1]],
                              p.substep_start[t[2]], start) &&
          !start.inside() && start.distance != 0.0) {
        pair.side = start.distance > 0.0 ? 1.0 : -1.0;
      }
    }
    TriangleProjection g;
    if (!projectOntoTriangle(p.position[v], p.position[t[0]], p.position[t[1]], p.position[t[2]],
                             g) ||
        !g.inside()) {
      continue;
    }
    // Gradients s n for the vertex and -s b_k n for the triangle corners (b_k barycentric): the
    // corrections are weighted by inverse mass and sum to zero momentum since sum b_k = 1.
    const double w = wv + g.weight[0] * g.weight[0] * wt[0] + g.weight[1] * g.weight[1] * wt[1] +
                     g.weight[2] * g.weight[2] * wt[2];
    if (w == 0.0) continue;
    const double c = pair.side * g.distance - (thickness - pair.allowance);
    if (c < 0.0) {
      const Vec3 direction = pair.side * g.normal;
      const double lambda = -c / w;
      p.position[v] += (wv * lambda) * direction;
      for (int k = 0; k < 3; ++k) p.position[t[k]] -= (wt[k] * g.weight[k] * lambda) * direction;
      state.depth -= c;
      state.normal = direction;
      max_change = std::max(max_change, -c);
    }
    if (state.depth > 0.0) {
      // Relative displacement of the vertex against the point of the triangle under it.
      Vec3 relative = p.position[v] - p.substep_start[v];
      for (int k = 0; k < 3; ++k) {
        relative -= g.weight[k] * (p.position[t[k]] - p.substep_start[t[k]]);
      }
      const Vec3 correction = frictionCorrection(relative, state, friction) / w;
      p.position[v] += wv * correction;
      for (int k = 0; k < 3; ++k) p.position[t[k]] -= (wt[k] * g.weight[k]) * correction;
    }
  }
  return max_change;
}

double SelfCollision::maxPenetration(const Particles& p, double thickness) const {
  double depth = 0.0;
  for (const VertexTrianglePair& pair : pairs_) {
    const int v = pair.vertex, a = pair.triangle[0], b = pair.triangle[1], c = pair.triangle[2];
    TriangleProjection g;
    if (!projectOntoTriangle(p.position[v], p.position[a], p.position[b], p.position[c], g) ||
        !g.inside()) {
      continue;
    }
    depth = std::max(depth, thickness - pair.side * g.distance);
  }
  return depth;
}

}  // namespace pbd_cloth
