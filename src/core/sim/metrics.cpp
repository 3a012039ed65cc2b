#include "pbd_cloth/sim/metrics.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <set>
#include <unordered_map>
#include <utility>

#include "pbd_cloth/collision/collisions.h"
#include "pbd_cloth/config/scene_config.h"

namespace pbd_cloth {

namespace {

// Max and mean |l - l0| / l0 over the stretch constraints [0, count) that have a particle the
// solver moves (links between two kinematic particles left out).
void strainOfFirst(const Particles& particles, const ClothTopology& topology, std::size_t count,
                   double& max_strain, double& mean_strain) {
  max_strain = 0.0;
  double sum = 0.0;
  std::size_t counted = 0;
  for (std::size_t c = 0; c < count; ++c) {
    const DistanceConstraint& con = topology.stretch[c];
    if (particles.isKinematic(con.i) && particles.isKinematic(con.j)) continue;
    const double length = (particles.position[con.i] - particles.position[con.j]).norm();
    const double strain = std::abs(length - con.rest_length) / con.rest_length;
    max_strain = std::max(max_strain, strain);
    sum += strain;
    ++counted;
  }
  mean_strain = counted == 0 ? 0.0 : sum / static_cast<double>(counted);
}

}  // namespace

void computeStrain(const Particles& particles, const ClothTopology& topology, double& max_strain,
                   double& mean_strain) {
  strainOfFirst(particles, topology, topology.stretch.size(), max_strain, mean_strain);
}

void computeStructuralStrain(const Particles& particles, const ClothTopology& topology,
                             double& max_strain, double& mean_strain) {
  const std::size_t count = std::min(
      topology.stretch.size(), static_cast<std::size_t>(std::max(0, topology.structural_count)));
  strainOfFirst(particles, topology, count, max_strain, mean_strain);
}

bool allFinite(const Particles& particles) {
  for (int i = 0; i < particles.size(); ++i) {
    if (!particles.position[i].allFinite() || !particles.velocity[i].allFinite()) return false;
  }
  return true;
}

namespace {

// Segment p-q against triangle (a,b,c), Moeller-Trumbore; a touching end point does not count.
bool segmentHitsTriangle(const Vec3& p, const Vec3& q, const Vec3& a, const Vec3& b,
                         const Vec3& c) {
  const Vec3 dir = q - p;
  const Vec3 e1 = b - a, e2 = c - a;
  const Vec3 pvec = dir.cross(e2);
  const double det = e1.dot(pvec);
  if (std::abs(det) < 1e-18) return false;  // parallel or degenerate triangle
  const double inv = 1.0 / det;
  const Vec3 tvec = p - a;
  const double u = tvec.dot(pvec) * inv;
  if (u < 0.0 || u > 1.0) return false;
  const Vec3 qvec = tvec.cross(e1);
  const double v = dir.dot(qvec) * inv;
  if (v < 0.0 || u + v > 1.0) return false;
  const double t = e2.dot(qvec) * inv;
  return t > 0.0 && t < 1.0;
}

std::int64_t cellKey(int x, int y, int z) {
  return (static_cast<std::int64_t>(x) * 73856093) ^ (static_cast<std::int64_t>(y) * 19349663) ^
         (static_cast<std::int64_t>(z) * 83492791);
}

}  // namespace

int countSelfIntersections(const Particles& particles, const ClothTopology& topology) {
  const auto& tri = topology.triangles;
  const int triangle_count = topology.triangleCount();
  if (triangle_count == 0) return 0;
  const Vec3Array& x = particles.position;

  std::set<std::pair<unsigned, unsigned>> edge_set;
  double cell = 0.0;
  for (int t = 0; t < triangle_count; ++t) {
    for (int e = 0; e < 3; ++e) {
      const unsigned a = tri[3 * t + e], b = tri[3 * t + (e + 1) % 3];
      edge_set.emplace(std::min(a, b), std::max(a, b));
      cell = std::max(cell, (x[a] - x[b]).norm());
    }
  }
  if (!(cell > 0.0) || !std::isfinite(cell)) return 0;

  // Uniform grid of cell size = longest edge; each triangle is filed in every cell its box covers.
  std::unordered_map<std::int64_t, std::vector<int>> grid;
  auto cellOf = [cell](double v) { return static_cast<int>(std::floor(v / cell)); };
  for (int t = 0; t < triangle_count; ++t) {
    Vec3 lo = x[tri[3 * t]], hi = lo;
    for (int k = 1; k < 3; ++k) {
      lo = lo.cwiseMin(x[tri[3 * t + k]]);
      hi = hi.cwiseMax(x[tri[3 * t + k]]);
    }
    for (int i = cellOf(lo.x()); i <= cellOf(hi.x()); ++i)
      for (int j = cellOf(lo.y()); j <= cellOf(hi.y()); ++j)
        for (int k = cellOf(lo.z()); k <= cellOf(hi.z()); ++k) grid[cellKey(i, j, k)].push_back(t);
  }

  std::set<std::pair<int, int>> hits;  // (edge index, triangle): counted once across cells
  int edge_index = 0;
  for (const auto& [a, b] : edge_set) {
    const Vec3 lo = x[a].cwiseMin(x[b]), hi = x[a].cwiseMax(x[b]);
    for (int i = cellOf(lo.x()); i <= cellOf(hi.x()); ++i)
      for (int j = cellOf(lo.y()); j <= cellOf(hi.y()); ++j)
        for (int k = cellOf(lo.z()); k <= cellOf(hi.z()); ++k) {
          auto it = grid.find(cellKey(i, j, k));
          if (it == grid.end()) continue;
          for (int t : it->second) {
            const unsigned t0 = tri[3 * t], t1 = tri[3 * t + 1], t2 = tri[3 * t + 2];
            if (a == t0 || a == t1 || a == t2 || b == t0 || b == t1 || b == t2) continue;
            if (segmentHitsTriangle(x[a], x[b], x[t0], x[t1], x[t2])) hits.emplace(edge_index, t);
          }
        }
    ++edge_index;
  }
  return static_cast<int>(hits.size());
}

Metrics measureMetrics(const Particles& particles, const ClothTopology& topology,
                       const Collisions& collisions, const SolverConfig& solver) {
  Metrics metrics;
  computeStrain(particles, topology, metrics.max_strain, metrics.mean_strain);
  computeStructuralStrain(particles, topology, metrics.structural_max_strain,
                          metrics.structural_mean_strain);
  metrics.max_penetration = collisions.maxPenetration(particles, topology);
  metrics.finite = allFinite(particles);
  // A diverged state has no meaningful geometry to intersect.
  metrics.self_intersections = metrics.finite ? countSelfIntersections(particles, topology) : -1;
  const Vec3& g = solver.gravity;
  for (int i = 0; i < particles.size(); ++i) {
    if (particles.isKinematic(i)) continue;
    metrics.kinetic_energy += 0.5 * particles.mass[i] * particles.velocity[i].squaredNorm();
    metrics.potential_energy -= particles.mass[i] * g.dot(particles.position[i]);
  }
  if (solver.method == Method::kMassSpring) {
    // Elastic energy of the explicit springs, so the baseline's energy is the full Hamiltonian.
    for (const DistanceConstraint& con : topology.stretch) {
      const double stretch =
          (particles.position[con.i] - particles.position[con.j]).norm() - con.rest_length;
      metrics.potential_energy += 0.5 * solver.spring_stiffness * stretch * stretch;
    }
  }
  metrics.energy = metrics.kinetic_energy + metrics.potential_energy;
  return metrics;
}

}  // namespace pbd_cloth
