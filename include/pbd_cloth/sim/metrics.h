// Accuracy metrics of a state, shared by the node's stats, cloth_bench and the tests.
#pragma once

#include "pbd_cloth/model/particles.h"

namespace pbd_cloth {

class Collisions;
struct SolverConfig;

struct Metrics {
  double max_strain = 0.0;   // max |l - l0| / l0 over stretch constraints
  double mean_strain = 0.0;  // mean |l - l0| / l0 over stretch constraints
  // The same over the structural links only (grid rows and columns, or every edge of a mesh
  // cloth): the strain of the issue 12 benchmark, which leaves the shear diagonals out.
  double structural_max_strain = 0.0;
  double structural_mean_strain = 0.0;
  double max_penetration = 0.0;  // m, deepest contact violation (obstacles, particles, cloth)
  int self_intersections = 0;    // edge-triangle crossings not sharing a vertex; -1 when !finite
  double kinetic_energy = 0.0;   // J
  double potential_energy =
      0.0;              // J, gravity relative to z = 0 (plus elastic energy of XPBD springs)
  double energy = 0.0;  // J, kinetic + potential
  bool finite = true;   // every position and velocity finite
};

// Strain over the stretch constraints: |l - l0| / l0. Links between two kinematic particles
// (pinned or grasped: both ends placed by a pin or a gripper, not by the solver) are left out:
// their length is what the pins and grippers make it, and two grasped neighbours would count as
// links the solver met exactly (or a gripper that brings two pins closer as its error).
void computeStrain(const Particles& particles, const ClothTopology& topology, double& max_strain,
                   double& mean_strain);

// The same over the structural constraints only (topology.stretch[0, structural_count)).
void computeStructuralStrain(const Particles& particles, const ClothTopology& topology,
                             double& max_strain, double& mean_strain);

// Number of (edge, triangle) pairs of the cloth mesh that intersect, excluding pairs sharing a
// vertex: the self-collision count of REFERENCE_CASES.md case 14. Uses a uniform grid broad phase.
int countSelfIntersections(const Particles& particles, const ClothTopology& topology);

bool allFinite(const Particles& particles);

// Every metric of a state: the strains, the deepest contact violation (collisions), whether it is
// finite, its self-intersections, and its energy under the solver's gravity (with the springs'
// elastic energy for solver.method mass_spring). Simulation::computeMetrics on its own state.
Metrics measureMetrics(const Particles& particles, const ClothTopology& topology,
                       const Collisions& collisions, const SolverConfig& solver);

}  // namespace pbd_cloth
