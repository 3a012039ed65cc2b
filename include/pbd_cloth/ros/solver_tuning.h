// The settings that can change while the simulation runs (cfg/Solver.cfg, dynamic_reconfigure),
// as a plain struct.
//
// Why a struct of its own: the dynamic_reconfigure generator names its class
// pbd_cloth::SolverConfig, the name the core's solver settings already have (scene_config.h). No
// file may include both, so solver_reconfigure.cpp sees only the generated class and this struct,
// and solver_tuning.cpp sees only this struct and the core.
#pragma once

#include <string>

namespace pbd_cloth {

class Simulation;

struct SolverTuning {
  int substeps = 10;                // solver.substeps
  int iterations = 1;               // solver.iterations
  double tolerance = 0.0;           // solver.tolerance (m)
  int ordering = 0;                 // solver.ordering: 0 gauss_seidel, 1 jacobi
  double relaxation = 1.0;          // solver.relaxation
  double damping = 0.0;             // solver.damping (1/s)
  double target_max_strain = 0.0;   // solver.target_max_strain (0: fixed substeps)
  double target_penetration = 0.0;  // solver.target_penetration (m)
  int min_substeps = 1;             // solver.min_substeps
  int max_substeps = 200;           // solver.max_substeps
  double stretch_compliance = 0.0;  // cloth.stretch_compliance (m/N)
  double bend_compliance = 1e-3;    // cloth.bend_compliance
  double friction_static = 0.5;     // cloth.friction.static
  double friction_kinetic = 0.4;    // cloth.friction.kinetic
};

// Which parts of SolverTuning a change touches (the dynamic_reconfigure levels in Solver.cfg).
enum TuningGroup : unsigned {
  kTuneSolver = 1u,      // substeps .. damping
  kTuneCompliance = 2u,  // stretch_compliance, bend_compliance
  kTuneFriction = 4u,    // friction_static, friction_kinetic
};

// The values the simulation runs with now.
SolverTuning tuningFromSimulation(const Simulation& sim);

// Applies the groups in `groups` to the simulation (from the next step on). A group the scene
// validation refuses is left as it was; its ConfigError message (naming the key and the allowed
// range) is appended to `errors`, one line per group. Returns true when every group was applied.
bool applyTuning(const SolverTuning& tuning, unsigned groups, Simulation& sim, std::string& errors);

}  // namespace pbd_cloth
