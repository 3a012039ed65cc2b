// Particle data in flat arrays (structure of arrays), indexed by particle: cloth particles first
// (index = r * cols + c), then granular particles.
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <vector>

namespace pbd_cloth {

using Vec3 = Eigen::Vector3d;
// Double precision throughout: at 1000 Hz x 100 substeps one substep moves a particle h^2 g = 1e-9
// m, below float32 resolution near 1 m (REFERENCE_CASES.md, "Precision").
using Vec3Array = std::vector<Vec3>;

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
// 0, linear in the positions (solver.cpp, projectBend).
struct BendConstraint {
  int index[4] = {0, 0, 0, 0};
  double weight[4] = {0.0, 0.0, 0.0, 0.0};  // K_k, sum zero
  double scale = 0.0;                       // sqrt(6 / (A0 + A1))
};

// Long-range attachment (Kim, Chentanez, Mueller 2012): a unilateral constraint
// C = max_length - |x_particle - x_anchor| >= 0 to a kinematic anchor, max_length = rest distance.
struct Tether {
  int particle = 0;
  int anchor = 0;
  double max_length = 0.0;
};

struct ClothTopology {
  int rows = 0;
  int cols = 0;
  std::vector<unsigned>
      triangles;  // 3 indices per triangle, counter-clockwise seen from +z of the grid
  std::vector<DistanceConstraint> stretch;  // structural first, then shear
  int structural_count = 0;
  std::vector<BendConstraint> bend;
  std::vector<Tether> tethers;  // rebuilt when the kinematic set changes
  int triangleCount() const { return static_cast<int>(triangles.size() / 3); }
};

}  // namespace pbd_cloth
