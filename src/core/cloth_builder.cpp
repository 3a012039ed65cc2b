#include "pbd_cloth/cloth_builder.h"

#include <algorithm>
#include <cmath>
#include <map>
#include <tuple>
#include <utility>

namespace pbd_cloth {

Eigen::Matrix3d rotationFromRpy(const Eigen::Vector3d& rpy) {
  return (Eigen::AngleAxisd(rpy.z(), Eigen::Vector3d::UnitZ()) *
          Eigen::AngleAxisd(rpy.y(), Eigen::Vector3d::UnitY()) *
          Eigen::AngleAxisd(rpy.x(), Eigen::Vector3d::UnitX()))
      .toRotationMatrix();
}

namespace {

// Cotangent of the angle between a and b; 0 for a degenerate angle (the hinge is then skipped).
// The test is relative (|a x b| against |a| |b|), so it means the same at any cloth spacing.
double cotangent(const Vec3& a, const Vec3& b) {
  const double sine = a.cross(b).norm();
  return sine > 1e-12 * a.norm() * b.norm() ? a.dot(b) / sine : 0.0;
}

void addTriangles(const ClothConfig& cloth, ClothTopology& topology) {
  const int cols = cloth.cols;
  for (int r = 0; r + 1 < cloth.rows; ++r) {
    for (int c = 0; c + 1 < cols; ++c) {
      const unsigned a = r * cols + c, b = a + 1, d = a + cols, e = d + 1;
      // Diagonals alternate in a checkerboard so the mesh has no preferred shear direction.
      // Both triangles wind counter-clockwise seen from the grid's +z (its front face).
      if ((r + c) % 2 == 0) {
        topology.triangles.insert(topology.triangles.end(), {a, d, e, a, e, b});
      } else {
        topology.triangles.insert(topology.triangles.end(), {a, d, b, b, d, e});
      }
    }
  }
}

// Order of the Gauss-Seidel sweep. Row by row from row 0 (the pinned top edge of the shipped
// scenes) so a pass still carries corrections down the cloth, but within a row in runs of
// constraints that share no particle: horizontal links of even columns, of odd columns, then every
// vertical link down to the next row. Consecutive projections of a run are independent, so the
// processor overlaps them instead of waiting for each one's square root and division to reach the
// next (a latency-bound loop otherwise; see doc/bench_summary.md, microbenchmarks).
void addStretch(const ClothConfig& cloth, const Vec3Array& x, ClothTopology& topology) {
  const int rows = cloth.rows, cols = cloth.cols;
  auto add = [&](int i, int j) { topology.stretch.push_back({i, j, (x[i] - x[j]).norm()}); };
  for (int r = 0; r < rows; ++r) {
    for (int parity = 0; parity < 2; ++parity) {
      for (int c = parity; c + 1 < cols; c += 2) add(r * cols + c, r * cols + c + 1);
    }
    if (r + 1 < rows) {
      for (int c = 0; c < cols; ++c) add(r * cols + c, (r + 1) * cols + c);
    }
  }
  topology.structural_count = static_cast<int>(topology.stretch.size());
  if (!cloth.shear) return;
  // Shear: the diagonal each cell's triangles share (the mesh edges, as Jolt does). Both diagonals
  // would make every cell a rigid planar frame and lock bending of an inextensible cloth. Cells
  // two apart share no particle: even cells of a row, then odd ones.
  for (int r = 0; r + 1 < rows; ++r) {
    for (int parity = 0; parity < 2; ++parity) {
      for (int c = parity; c + 1 < cols; c += 2) {
        const int i = r * cols + c;
        if ((r + c) % 2 == 0) {
          add(i, i + cols + 1);
        } else {
          add(i + 1, i + cols);
        }
      }
    }
  }
}

void addBending(const Vec3Array& x, ClothTopology& topology) {
  // Each interior edge is shared by two triangles: a hinge with the two opposite vertices.
  std::map<std::pair<unsigned, unsigned>, std::pair<int, int>> opposite;  // edge -> (v2, v3)
  const auto& t = topology.triangles;
  for (std::size_t k = 0; k < t.size(); k += 3) {
    for (int e = 0; e < 3; ++e) {
      unsigned a = t[k + e], b = t[k + (e + 1) % 3];
      const int other = static_cast<int>(t[k + (e + 2) % 3]);
      auto key = std::make_pair(std::min(a, b), std::max(a, b));
      auto it = opposite.find(key);
      if (it == opposite.end()) {
        opposite.emplace(key, std::make_pair(other, -1));
      } else {
        it->second.second = other;
      }
    }
  }
  for (const auto& [edge, opp] : opposite) {
    if (opp.second < 0) continue;  // boundary edge
    BendConstraint bend;
    if (makeBendConstraint(x, static_cast<int>(edge.first), static_cast<int>(edge.second),
                           opp.first, opp.second, bend)) {
      topology.bend.push_back(bend);
    }
  }
  // Sweep order as for the stretch links: row by row, and within a row in runs of hinges three
  // columns apart of one kind (the edge along the row, across it, or the cell diagonal), which
  // share no particle, so consecutive projections are independent.
  const int cols = topology.cols;
  const auto key = [cols](const BendConstraint& b) {
    const int r0 = b.index[0] / cols, c0 = b.index[0] % cols;
    const int r1 = b.index[1] / cols, c1 = b.index[1] % cols;
    const int kind = r0 == r1 ? 0 : (c0 == c1 ? 1 : 2);
    const int c = std::min(c0, c1);
    return std::make_tuple(std::min(r0, r1), kind, c % 3, c);
  };
  std::stable_sort(
      topology.bend.begin(), topology.bend.end(),
      [&key](const BendConstraint& a, const BendConstraint& b) { return key(a) < key(b); });
}

}  // namespace

bool makeBendConstraint(const Vec3Array& rest, int i0, int i1, int i2, int i3,
                        BendConstraint& out) {
  const Vec3 &x0 = rest[i0], &x1 = rest[i1], &x2 = rest[i2], &x3 = rest[i3];
  const Vec3 e0 = x1 - x0, e1 = x2 - x0, e2 = x3 - x0, e3 = x2 - x1, e4 = x3 - x1;
  const double area0 = 0.5 * e0.cross(e1).norm();
  const double area1 = 0.5 * e0.cross(e2).norm();
  // Zero-area (or NaN) triangle: no hinge. Relative to the squared edge lengths, so a sliver is
  // recognized at any spacing; written as !(a > b) so that NaN is refused too.
  const double edge2 = e0.squaredNorm() + e1.squaredNorm() + e2.squaredNorm();
  if (!(area0 > 1e-12 * edge2) || !(area1 > 1e-12 * edge2)) return false;
  // Cotangents of the angles at x0 and x1 in both triangles (Wardetzky et al. 2007, eq. 6).
  const double c01 = cotangent(e0, e1), c02 = cotangent(e0, e2);
  const double c03 = cotangent(-e0, e3), c04 = cotangent(-e0, e4);
  out.index[0] = i0;
  out.index[1] = i1;
  out.index[2] = i2;
  out.index[3] = i3;
  out.weight[0] = c03 + c04;
  out.weight[1] = c01 + c02;
  out.weight[2] = -c01 - c03;
  out.weight[3] = -c02 - c04;
  out.scale = std::sqrt(6.0 / (area0 + area1));
  return true;
}

void buildScene(const SceneConfig& scene, Particles& particles, ClothTopology& topology) {
  const ClothConfig& cloth = scene.cloth;
  const GranularConfig& granular = scene.granular;
  const int cloth_count = cloth.rows * cloth.cols;
  particles.resize(cloth_count + granular.count);
  particles.cloth_count = cloth_count;
  topology = ClothTopology();
  topology.rows = cloth.rows;
  topology.cols = cloth.cols;

  const Eigen::Matrix3d rotation = rotationFromRpy(cloth.rpy);
  const double particle_mass = cloth.mass / cloth_count;
  for (int r = 0; r < cloth.rows; ++r) {
    for (int c = 0; c < cloth.cols; ++c) {
      const int i = r * cloth.cols + c;
      particles.position[i] =
          cloth.origin + rotation * Vec3(c * cloth.spacing, -r * cloth.spacing, 0.0);
      particles.mass[i] = particle_mass;
      particles.radius[i] = cloth.thickness;
    }
  }
  for (const auto& [index, kg] : cloth.point_masses) particles.mass[index] = kg;

  // Granular particles on a simple cubic lattice of pitch 2.2 r inside the region, filled x first.
  const double pitch = 2.2 * granular.radius;
  const Vec3 extent = granular.region_max - granular.region_min;
  const int nx = std::max(1, static_cast<int>(extent.x() / pitch));
  const int ny = std::max(1, static_cast<int>(extent.y() / pitch));
  for (int k = 0; k < granular.count; ++k) {
    const int i = cloth_count + k;
    const int ix = k % nx, iy = (k / nx) % ny, iz = k / (nx * ny);
    particles.position[i] = granular.region_min +
                            Vec3(granular.radius, granular.radius, granular.radius) +
                            pitch * Vec3(ix, iy, iz);
    particles.mass[i] = granular.mass;
    particles.radius[i] = granular.radius;
  }

  for (int i = 0; i < particles.size(); ++i) particles.inverse_mass[i] = 1.0 / particles.mass[i];
  for (int index : cloth.pinned) particles.inverse_mass[index] = 0.0;
  particles.substep_start = particles.position;
  particles.step_start = particles.position;
  particles.kinematic_from = particles.position;
  particles.kinematic_to = particles.position;

  addTriangles(cloth, topology);
  addStretch(cloth, particles.position, topology);
  if (cloth.bend_compliance >= 0.0) addBending(particles.position, topology);
  if (cloth.tethers) buildTethers(particles, topology, cloth.spacing, topology.tethers);
}

void buildTethers(const Particles& particles, const ClothTopology& topology, double spacing,
                  std::vector<Tether>& tethers) {
  tethers.clear();
  std::vector<int> anchors;
  for (int i = 0; i < particles.cloth_count; ++i) {
    if (particles.isKinematic(i)) anchors.push_back(i);
  }
  const int cols = topology.cols;
  for (int i = 0; i < particles.cloth_count; ++i) {
    if (particles.isKinematic(i)) continue;
    for (int a : anchors) {
      // Geodesic distance on the flat rest grid (the cloth is built flat).
      const double dr = (i / cols) - (a / cols), dc = (i % cols) - (a % cols);
      tethers.push_back({i, a, spacing * std::sqrt(dr * dr + dc * dc)});
    }
  }
}

}  // namespace pbd_cloth
