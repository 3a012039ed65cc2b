// Particle data in flat arrays (structure of arrays), indexed by particle: cloth particles first
// (index = r * cols + c), then granular particles.
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <vector>

#include "pbd_cloth/geometry/vector_types.h"

namespace pbd_cloth {

struct Particles {
  Vec3Array position;        // x (m)
  Vec3Array velocity;        // v (m/s); for Verlet the half-step velocity (x_n - x_{n-1}) / h
  Vec3Array substep_start;   // x at the start of the current substep (Verlet's x_prev)
  Vec3Array step_start;      // x at the start of the step: friction displacement, collision side
  Vec3Array kinematic_from;  // kinematic particles: position at the start of the step
  Vec3Array kinematic_to;    // kinematic particles: prescribed position at the end of the step
  std::vector<double> mass;  // kg (kept while kinematic so release restores it)
  std::vector<double> inverse_mass;  // 1/kg; 0 = kinematic (pinned or grasped)
  std::vector<double> radius;        // contact radius (m): cloth thickness or granular radius
  int cloth_count = 0;               // particles [0, cloth_count) belong to the cloth grid

  int size() const { return static_cast<int>(position.size()); }
  bool isKinematic(int i) const { return inverse_mass[i] == 0.0; }
  void resize(int n);
};

// Stretch constraint (structural or shear): C = |x_i - x_j| - rest_length = 0 (seed, C2).
struct DistanceConstraint {
  int i = 0;
  int j = 0;
  double rest_length = 0.0;
};

// Isometric bending (Bergou et al. 2006, "A quadratic bending model for inextensible surfaces";
// Wardetzky et al. 2007 cotangent weights) on the hinge of two triangles (x0,x1,x2) and (x0,x1,x3)
// sharing edge x0-x1. The mean-curvature vector b = sum_k K_k x_k vanishes on the flat rest state;
// the bending energy is E = 3/(A0+A1) |b|^2 = |C|^2 / 2 with the vector constraint C = scale * b =
// 0, linear in the positions (bend_projection.cpp, projectBend).
struct BendConstraint {
  int index[4] = {0, 0, 0, 0};
  double weight[4] = {0.0, 0.0, 0.0, 0.0};  // K_k, sum zero
  double scale = 0.0;                       // sqrt(6 / (A0 + A1))
};

// A hinge with a kinematic corner and a free one: its multiplier is a reaction on the kinematic
// corner (Solver::startReactions lists these hinges; makeFlatHinge marks them).
inline bool joinsKinematicToFree(const BendConstraint& con, const double* inverse_mass) {
  int kinematic = 0;
  for (int v = 0; v < 4; ++v) kinematic += inverse_mass[con.index[v]] == 0.0;
  return kinematic > 0 && kinematic < 4;
}

// Rest term of a hinge of a mesh cloth whose rest shape is not flat (cloth.mesh): the rest
// mean-curvature vector b0, stored as its components in the frames of the hinge's two triangles
// (edge direction, in-plane normal to the edge, triangle normal). The projection asks for
// C = scale (b - b0'), b0' = the mean of b0 carried along by either triangle's current frame, so
// a curved or folded hinge keeps its rest angle however the cloth moves (bend_projection.cpp,
// projectBend). Flat hinges (every hinge of the grid) have none and keep C = scale b.
struct BendRest {
  bool curved = false;
  Vec3 in_first = Vec3::Zero();   // b0 in the frame of triangle (x0, x1, x2)
  Vec3 in_second = Vec3::Zero();  // b0 in the frame of triangle (x0, x1, x3)
};

// Long-range attachment (Kim, Chentanez, Mueller 2012): a unilateral constraint
// C = max_length - |x_particle - x_anchor| >= 0 to a kinematic anchor, max_length = rest distance.
struct Tether {
  int particle = 0;
  int anchor = 0;
  double max_length = 0.0;
};

struct ClothTopology {
  int rows = 0;  // the grid's; 0 for a mesh cloth
  int cols = 0;
  // 3 indices per triangle, counter-clockwise seen from +z of the grid; a mesh's in file order.
  std::vector<unsigned> triangles;
  std::vector<DistanceConstraint> stretch;  // structural first, then shear
  int structural_count = 0;
  std::vector<BendConstraint> bend;
  // Grid cloths with at least 32 rows: `bend` grouped into tasks for threads (solver.threads),
  // task t being bend[bend_task[t] .. bend_task[t + 1]). Tasks [0, bend_blocks) hold the hinges
  // within one block of rows, the rest those across the seam between two blocks: the tasks of
  // each group share no particle. Empty: one sequence.
  std::vector<int> bend_task;
  int bend_blocks = 0;
  // Mesh cloths only: one entry per hinge of `bend` (empty for the grid, whose rest is flat).
  std::vector<BendRest> bend_rest;
  // Mesh cloths only (the grid uses rows and cols): for each particle, the sorted particles that
  // share a triangle or a hinge with it (CSR: near_list[near_offsets[i] .. near_offsets[i+1])).
  // Edge-edge self-contacts between such neighbours are left out, as for neighbouring grid cells.
  std::vector<int> near_offsets;
  std::vector<int> near_list;
  std::vector<Tether> tethers;  // rebuilt when the kinematic set changes
  bool from_mesh = false;       // built from cloth.mesh (rows = cols = 0)
  // Particles a and b share a triangle or a hinge (mesh cloths).
  bool meshNear(int a, int b) const;
  int triangleCount() const { return static_cast<int>(triangles.size() / 3); }
};

}  // namespace pbd_cloth
