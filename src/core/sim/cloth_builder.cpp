#include "pbd_cloth/sim/cloth_builder.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <map>
#include <tuple>
#include <utility>

#include "pbd_cloth/constraints/tethers.h"
#include "pbd_cloth/sim/mesh_cloth.h"

namespace pbd_cloth {

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
  // Shear: by default the diagonal each cell's triangles share (the mesh edges, as Jolt does).
  // Both diagonals (cloth.shear_diagonals: 2, the link set of Bullet's and Bender's cloth, and of
  // the issue 12 benchmark) make every cell a rigid planar frame: an inextensible cloth then folds
  // only along the grid lines between cells. Cells two apart share no particle: even cells of a
  // row, then odd ones.
  // With both, every main diagonal of a row (cells next to each other share none), then every
  // anti-diagonal: runs whose particle indices step by one, four of which the projection loads as
  // whole registers (stretch_links.h); one diagonal per cell steps by two, as even and odd cells.
  const bool both = cloth.shear_diagonals == 2;
  for (int r = 0; r + 1 < rows; ++r) {
    if (both) {
      for (int c = 0; c + 1 < cols; ++c) add(r * cols + c, r * cols + c + cols + 1);
      for (int c = 0; c + 1 < cols; ++c) add(r * cols + c + 1, r * cols + c + cols);
      continue;
    }
    for (int parity = 0; parity < 2; ++parity) {
      for (int c = parity; c + 1 < cols; c += 2) {
        const int i = r * cols + c;
        const bool main_diagonal = (r + c) % 2 == 0;  // the triangles' shared edge is a-e
        if (main_diagonal) {
          add(i, i + cols + 1);
        } else {
          add(i + 1, i + cols);
        }
      }
    }
  }
}

void groupHingesIntoTasks(ClothTopology& topology);

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
  groupHingesIntoTasks(topology);
}

// Tasks for threads, as the stretch links' (stretch_links.cpp): eight blocks of rows of equal
// size where the grid has at least 32 rows (so at least four rows a block), the hinges wholly
// inside a block first, block by block, then those across each seam. A hinge spans at most three
// rows, so hinges of different blocks share no particle, nor do those of different seams (four rows
// apart). The order within a task is the sweep order above; one thread runs the tasks in this order
// too, so every thread count gives the same result.
void groupHingesIntoTasks(ClothTopology& topology) {
  topology.bend_task.clear();
  topology.bend_blocks = 0;
  const int rows = topology.rows, cols = topology.cols;
  if (rows < 32 || cols <= 0 || topology.bend.empty()) return;
  // Block b: rows [b rows / 8, (b + 1) rows / 8), so row r is in block (8 (r + 1) - 1) / rows.
  const int blocks = 8;
  const int count = static_cast<int>(topology.bend.size());
  std::vector<int> task_of(count);
  for (int c = 0; c < count; ++c) {
    int lowest = blocks, highest = -1;
    for (int k = 0; k < 4; ++k) {
      const int block = (blocks * (topology.bend[c].index[k] / cols + 1) - 1) / rows;
      lowest = std::min(lowest, block);
      highest = std::max(highest, block);
    }
    if (highest - lowest > 1 || lowest < 0 || highest >= blocks) return;  // off the grid: one task
    task_of[c] = lowest == highest ? lowest : blocks + lowest;
  }
  const int tasks = 2 * blocks - 1;
  std::vector<int> start(tasks + 1, 0);
  for (int c = 0; c < count; ++c) ++start[task_of[c] + 1];
  for (int t = 0; t < tasks; ++t) start[t + 1] += start[t];
  std::vector<BendConstraint> grouped(count);
  std::vector<int> next(start.begin(), start.end() - 1);
  for (int c = 0; c < count; ++c) grouped[next[task_of[c]]++] = topology.bend[c];
  topology.bend.swap(grouped);
  topology.bend_task = start;
  topology.bend_blocks = blocks;
}

// --- Mesh cloths (cloth.mesh)
// ----------------------------------------------------------------------

// Frame of the triangle (x0, x1, x2) at its edge x0-x1: edge direction, in-plane normal to the
// edge, triangle normal (the columns). `flip` mirrors the normal for the hinge's second triangle
// (x0, x1, x3), so on a flat hinge both frames are the same.
Eigen::Matrix3d hingeFrame(const Vec3& x0, const Vec3& x1, const Vec3& x2, bool flip) {
  const Vec3 t = (x1 - x0).normalized();
  Vec3 n = t.cross(x2 - x0).normalized();
  if (flip) n = -n;
  Eigen::Matrix3d frame;
  frame.col(0) = t;
  frame.col(1) = n.cross(t);
  frame.col(2) = n;
  return frame;
}

// Stretch along every edge of the triangles, once (sorted by vertex pair: a deterministic order).
void addMeshStretch(const Vec3Array& x, ClothTopology& topology) {
  std::vector<std::pair<int, int>> edges;
  const auto& t = topology.triangles;
  edges.reserve(t.size());
  for (std::size_t k = 0; k < t.size(); k += 3) {
    for (int e = 0; e < 3; ++e) {
      const int a = static_cast<int>(t[k + e]), b = static_cast<int>(t[k + (e + 1) % 3]);
      edges.emplace_back(std::min(a, b), std::max(a, b));
    }
  }
  std::sort(edges.begin(), edges.end());
  edges.erase(std::unique(edges.begin(), edges.end()), edges.end());
  for (const auto& [i, j] : edges) topology.stretch.push_back({i, j, (x[i] - x[j]).norm()});
  topology.structural_count = static_cast<int>(topology.stretch.size());
}

// A hinge on every edge shared by exactly two triangles, at the mesh's own rest angle: the rest
// mean-curvature vector b0 is kept in both triangles' frames (BendRest). Edges of more than two
// triangles (non-manifold) get none: which pair of faces would bend is undefined.
void addMeshBending(const Vec3Array& x, ClothTopology& topology) {
  std::map<std::pair<unsigned, unsigned>, std::vector<int>> opposite;  // edge -> opposite vertices
  const auto& t = topology.triangles;
  for (std::size_t k = 0; k < t.size(); k += 3) {
    for (int e = 0; e < 3; ++e) {
      const unsigned a = t[k + e], b = t[k + (e + 1) % 3];
      opposite[std::make_pair(std::min(a, b), std::max(a, b))].push_back(
          static_cast<int>(t[k + (e + 2) % 3]));
    }
  }
  for (const auto& [edge, opp] : opposite) {
    if (opp.size() != 2) continue;  // boundary or non-manifold edge
    const int i0 = static_cast<int>(edge.first), i1 = static_cast<int>(edge.second);
    BendConstraint bend;
    if (!makeBendConstraint(x, i0, i1, opp[0], opp[1], bend)) continue;
    BendRest rest;
    const Vec3 b0 = bend.weight[1] * (x[i1] - x[i0]) + bend.weight[2] * (x[opp[0]] - x[i0]) +
                    bend.weight[3] * (x[opp[1]] - x[i0]);
    // Flat within rounding (relative to the edge): the grid's C = scale b, no frames needed.
    if (b0.norm() > 1e-9 * (x[i1] - x[i0]).norm()) {
      rest.curved = true;
      rest.in_first = hingeFrame(x[i0], x[i1], x[opp[0]], false).transpose() * b0;
      rest.in_second = hingeFrame(x[i0], x[i1], x[opp[1]], true).transpose() * b0;
    }
    topology.bend.push_back(bend);
    topology.bend_rest.push_back(rest);
  }
}

// For each particle, the particles that share a triangle or a hinge with it (sorted).
void addMeshNeighbours(int count, ClothTopology& topology) {
  std::vector<std::vector<int>> near(count);
  const auto& t = topology.triangles;
  for (std::size_t k = 0; k < t.size(); k += 3) {
    for (int a = 0; a < 3; ++a) {
      for (int b = 0; b < 3; ++b) {
        if (a != b) near[t[k + a]].push_back(static_cast<int>(t[k + b]));
      }
    }
  }
  // The opposite corners of each pair of triangles sharing an edge (with or without bending).
  std::vector<std::array<int, 3>> sides;  // edge (a, b), opposite corner
  sides.reserve(t.size());
  for (std::size_t k = 0; k < t.size(); k += 3) {
    for (int e = 0; e < 3; ++e) {
      const int a = static_cast<int>(t[k + e]), b = static_cast<int>(t[k + (e + 1) % 3]);
      sides.push_back({std::min(a, b), std::max(a, b), static_cast<int>(t[k + (e + 2) % 3])});
    }
  }
  std::sort(sides.begin(), sides.end());
  for (std::size_t k = 0; k < sides.size();) {
    std::size_t end = k + 1;
    while (end < sides.size() && sides[end][0] == sides[k][0] && sides[end][1] == sides[k][1]) {
      ++end;
    }
    for (std::size_t u = k; u < end; ++u) {
      for (std::size_t v = k; v < end; ++v) {
        if (u != v) near[sides[u][2]].push_back(sides[v][2]);
      }
    }
    k = end;
  }
  topology.near_offsets.assign(1, 0);
  topology.near_list.clear();
  for (auto& list : near) {
    std::sort(list.begin(), list.end());
    list.erase(std::unique(list.begin(), list.end()), list.end());
    topology.near_list.insert(topology.near_list.end(), list.begin(), list.end());
    topology.near_offsets.push_back(static_cast<int>(topology.near_list.size()));
  }
}

// Particles at the file's vertices placed by origin, rpy and mesh_scale; masses lumped from the
// triangle areas (each triangle gives a third of its share of cloth.mass to each corner), so an
// irregular mesh carries its mass where its area is, as the grid does.
void placeMeshParticles(const ClothConfig& cloth, const ClothMesh& mesh, Particles& particles) {
  const Eigen::Matrix3d rotation = rotationFromRpy(cloth.rpy);
  const int count = static_cast<int>(mesh.vertices.size());
  for (int i = 0; i < count; ++i) {
    particles.position[i] = meshStartPosition(cloth, rotation, mesh.vertices[i]);
    particles.mass[i] = 0.0;
    particles.radius[i] = cloth.thickness;
  }
  const auto& t = mesh.triangles;
  double total_area = 0.0;
  std::vector<double> area(t.size() / 3);
  for (std::size_t k = 0; k < area.size(); ++k) {
    const Vec3& a = mesh.vertices[t[3 * k]];
    area[k] = 0.5 * (mesh.vertices[t[3 * k + 1]] - a).cross(mesh.vertices[t[3 * k + 2]] - a).norm();
    total_area += area[k];
  }
  for (std::size_t k = 0; k < area.size(); ++k) {
    const double share = cloth.mass * area[k] / total_area / 3.0;
    for (int c = 0; c < 3; ++c) particles.mass[t[3 * k + c]] += share;
  }
}

}  // namespace

bool makeBendConstraint(const Vec3Array& rest, int i0, int i1, int i2, int i3,
                        BendConstraint& out) {
  // The two triangles are one (a mesh listing a triangle twice): no hinge, and the projection
  // may take a hinge's four corners to be four particles (flat_hinges.h).
  if (i0 == i1 || i2 == i3 || i2 == i0 || i2 == i1 || i3 == i0 || i3 == i1) return false;
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

std::vector<Rod> buildRopes(const SceneConfig& scene, int first_particle) {
  std::vector<Rod> ropes;
  for (const RopeConfig& config : scene.ropes) {
    RodMaterial material;
    material.radius = config.radius;
    material.density = config.density;
    material.young_modulus = config.young_modulus;
    material.shear_modulus = config.shear_modulus;
    material.stretch_compliance = config.stretch_compliance;
    Rod rope = makeRod(config.restPoints(), material);
    rope.first_particle = first_particle;
    for (int index : config.pinned) rope.fixParticle(index);
    first_particle += rope.size();
    ropes.push_back(std::move(rope));
  }
  return ropes;
}

void buildScene(const SceneConfig& scene, Particles& particles, ClothTopology& topology) {
  const ClothConfig& cloth = scene.cloth;
  const GranularConfig& granular = scene.granular;
  const ClothMesh* mesh = cloth.mesh.empty() ? nullptr : cloth.mesh_data.get();
  const int cloth_count = mesh ? static_cast<int>(mesh->vertices.size()) : cloth.rows * cloth.cols;
  const std::vector<Rod> ropes = buildRopes(scene, cloth_count);
  int rope_count = 0;
  for (const Rod& rope : ropes) rope_count += rope.size();
  particles.resize(cloth_count + rope_count + granular.count);
  particles.cloth_count = cloth_count;
  topology = ClothTopology();

  if (mesh) {
    topology.from_mesh = true;
    placeMeshParticles(cloth, *mesh, particles);
  } else {
    topology.rows = cloth.rows;
    topology.cols = cloth.cols;
    const Eigen::Matrix3d rotation = rotationFromRpy(cloth.rpy);
    const double particle_mass = cloth.mass / cloth_count;
    for (int r = 0; r < cloth.rows; ++r) {
      for (int c = 0; c < cloth.cols; ++c) {
        const int i = r * cloth.cols + c;
        particles.position[i] = gridStartPosition(cloth, rotation, r, c);
        particles.mass[i] = particle_mass;
        particles.radius[i] = cloth.thickness;
      }
    }
  }
  for (const auto& [index, kg] : cloth.point_masses) particles.mass[index] = kg;
  for (const Rod& rope : ropes) {
    for (int k = 0; k < rope.size(); ++k) {
      const int i = rope.first_particle + k;
      particles.position[i] = rope.position[k];
      particles.mass[i] = rope.mass[k];
      particles.radius[i] = rope.radius;
    }
  }

  // Granular particles on a simple cubic lattice of pitch 2.2 r inside the region, filled x first.
  const double pitch = 2.2 * granular.radius;
  const Vec3 extent = granular.region_max - granular.region_min;
  const int nx = std::max(1, static_cast<int>(extent.x() / pitch));
  const int ny = std::max(1, static_cast<int>(extent.y() / pitch));
  for (int k = 0; k < granular.count; ++k) {
    const int i = cloth_count + rope_count + k;
    const int ix = k % nx, iy = (k / nx) % ny, iz = k / (nx * ny);
    particles.position[i] = granular.region_min +
                            Vec3(granular.radius, granular.radius, granular.radius) +
                            pitch * Vec3(ix, iy, iz);
    particles.mass[i] = granular.mass;
    particles.radius[i] = granular.radius;
  }

  for (int i = 0; i < particles.size(); ++i) particles.inverse_mass[i] = 1.0 / particles.mass[i];
  for (int index : cloth.pinned) particles.inverse_mass[index] = 0.0;
  for (std::size_t r = 0; r < ropes.size(); ++r) {
    for (int index : scene.ropes[r].pinned) {
      particles.inverse_mass[ropes[r].first_particle + index] = 0.0;
    }
  }
  particles.substep_start = particles.position;
  particles.step_start = particles.position;
  particles.kinematic_from = particles.position;
  particles.kinematic_to = particles.position;

  if (mesh) {
    topology.triangles = mesh->triangles;
    addMeshStretch(particles.position, topology);
    addMeshNeighbours(cloth_count, topology);
  } else {
    addTriangles(cloth, topology);
    addStretch(cloth, particles.position, topology);
  }
  if (cloth.bend_compliance >= 0.0) buildBending(particles.position, topology);
  if (cloth.tethers) {
    TetherBuilder tethers;
    tethers.build(particles, topology, cloth.spacing, topology.tethers);
  }
}

void buildBending(const Vec3Array& rest, ClothTopology& topology) {
  topology.bend.clear();
  topology.bend_rest.clear();
  topology.bend_task.clear();
  topology.bend_blocks = 0;
  if (topology.from_mesh) {
    addMeshBending(rest, topology);
  } else {
    addBending(rest, topology);
  }
}

}  // namespace pbd_cloth
