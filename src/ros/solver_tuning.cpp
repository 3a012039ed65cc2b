#include "pbd_cloth/ros/solver_tuning.h"

#include "pbd_cloth/sim/simulation.h"

namespace pbd_cloth {

SolverTuning tuningFromSimulation(const Simulation& sim) {
  const SolverConfig& solver = sim.scene().solver;
  const ClothConfig& cloth = sim.scene().cloth;
  SolverTuning tuning;
  tuning.substeps = solver.substeps;
  tuning.iterations = solver.iterations;
  tuning.tolerance = solver.tolerance;
  tuning.ordering = solver.ordering == Ordering::kJacobi ? 1 : 0;
  tuning.relaxation = solver.relaxation;
  tuning.damping = solver.damping;
  tuning.target_max_strain = solver.target_max_strain;
  tuning.target_penetration = solver.target_penetration;
  tuning.min_substeps = solver.min_substeps;
  tuning.max_substeps = solver.max_substeps;
  tuning.stretch_compliance = cloth.stretch_compliance;
  tuning.bend_compliance = cloth.bend_compliance;
  tuning.friction_static = cloth.friction.static_coefficient;
  tuning.friction_kinetic = cloth.friction.kinetic_coefficient;
  return tuning;
}

bool applyTuning(const SolverTuning& tuning, unsigned groups, Simulation& sim,
                 std::string& errors) {
  bool all_applied = true;
  // Each group on its own: a refused friction pair should not also throw away a new substep count.
  const auto attempt = [&](unsigned group, auto&& apply) {
    if ((groups & group) == 0) return;
    try {
      apply();
    } catch (const ConfigError& error) {
      errors += std::string(errors.empty() ? "" : "\n") + error.what();
      all_applied = false;
    }
  };
  attempt(kTuneSolver, [&] {
    SolverConfig solver = sim.scene().solver;  // method, gravity, ... stay as they are
    solver.substeps = tuning.substeps;
    solver.iterations = tuning.iterations;
    solver.tolerance = tuning.tolerance;
    solver.ordering = tuning.ordering == 1 ? Ordering::kJacobi : Ordering::kGaussSeidel;
    solver.relaxation = tuning.relaxation;
    solver.damping = tuning.damping;
    solver.target_max_strain = tuning.target_max_strain;
    solver.target_penetration = tuning.target_penetration;
    solver.min_substeps = tuning.min_substeps;
    solver.max_substeps = tuning.max_substeps;
    sim.setSolverConfig(solver);
  });
  attempt(kTuneCompliance,
          [&] { sim.setClothCompliance(tuning.stretch_compliance, tuning.bend_compliance); });
  attempt(kTuneFriction, [&] {
    FrictionConfig friction;
    friction.static_coefficient = tuning.friction_static;
    friction.kinetic_coefficient = tuning.friction_kinetic;
    sim.setFriction(friction);
  });
  return all_applied;
}

}  // namespace pbd_cloth
