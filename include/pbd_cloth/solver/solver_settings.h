// The solver's settings: the method, its passes and its options, as the scene's `solver:` block
// gives them (config/scene_config.h holds one; scene_yaml.cpp reads it; validate() checks its
// ranges). A plain struct of the solver's own, so the solver never sees the scene configuration
// (doc/design.md, "Rules of the house").
#pragma once

#include <Eigen/Core>

namespace pbd_cloth {

enum class Method {
  kVerlet,      // the seed: Verlet integration, constraints projected rigidly, relaxation loop
  kPbd,         // Mueller et al. 2007: stiffness in [0,1], corrected for the iteration count
  kXpbd,        // Macklin et al. 2016: compliance, one Lagrange multiplier per constraint
  kMassSpring,  // explicit springs and dampers, symplectic Euler: the penalty baseline
};
enum class Ordering { kGaussSeidel, kJacobi };

const char* toString(Method method);
const char* toString(Ordering ordering);

// Upper limit of solver.substeps, solver.iterations and solver.search_window: not physics, but a
// typo like substeps: 50000 would otherwise stall the node before anyone sees an error.
constexpr int kMaxPasses = 1000;

struct SolverConfig {
  Method method = Method::kXpbd;               // solver.method
  int substeps = 10;                           // solver.substeps, per step
  int iterations = 1;                          // solver.iterations, passes per substep
  double tolerance = 0.0;                      // solver.tolerance (m); > 0: adaptive
  Ordering ordering = Ordering::kGaussSeidel;  // solver.ordering
  double relaxation = 1.0;                     // solver.relaxation, Jacobi factor in (0,2)
  bool jacobi_averaging = true;                // solver.jacobi_averaging (eq. 48 survey)
  Eigen::Vector3d gravity{0.0, 0.0, -9.81};    // solver.gravity (m/s^2)
  double damping = 0.0;                        // solver.damping (1/s)
  double stretch_stiffness = 1.0;              // solver.stretch_stiffness, pbd only, [0,1]
  double bend_stiffness = 0.1;                 // solver.bend_stiffness, pbd only, [0,1]
  double spring_stiffness = 1.0e4;             // solver.spring_stiffness (N/m), mass_spring
  double spring_damping = 0.0;                 // solver.spring_damping (N s/m), mass_spring
  // 0.01: on the 50 x 50 hanging cloth 1.0 already diverges at 240 substeps (scripts/method_table).
  double bend_spring_stiffness = 0.01;  // solver.bend_spring_stiffness, mass_spring
  // solver.levels: levels of long-range links of the grid cloth's stretch solve (coarse_levels.h,
  // after hierarchical PBD), each pass coarsest first. 0 = off (the default). Grid cloth and zero
  // stretch compliance only: the links are inextensible.
  int levels = 0;
  // Accuracy on demand (sim/accuracy_controller.h): solver.target_max_strain (largest structural
  // strain, e.g. 0.01 for 1 %) and solver.target_penetration (m); 0 = no target. With either
  // set, each step's substeps are chosen within solver.min_substeps .. solver.max_substeps
  // (solver.substeps is where they start) so that the state reported meets the targets.
  double target_max_strain = 0.0;
  double target_penetration = 0.0;
  int min_substeps = 1;
  int max_substeps = 200;
  // solver.max_speed (m/s): a free particle faster than this after a step means the step blew up
  // (its kinetic energy m v^2 / 2 per particle is out of bounds). Where fault recovery is on (the
  // node), that step is undone: Simulation::step, "Faults". Nothing a robot handles moves a cloth
  // at 100 m/s; a gripper jumping 1 m in one 60 Hz step drags its neighbours at about 60 m/s.
  double max_speed = 100.0;
  // Project the stretch links four at a time with AVX2 where the processor has it, eight at a
  // time with AVX-512 where it has that (stretch_links.h; bit-identical to the portable loop).
  // false: always the portable loop. Not a scene key: cloth_bench --no-simd compares the paths.
  bool simd = true;
  // false keeps the stretch links and the flat hinges at AVX2 on a processor with AVX-512 (the
  // same results to the bit; cloth_bench --no-avx512; doc/journal.md, "2026-11-29: Eight links
  // a register" and "2026-11-29: Flat hinges through masked accesses").
  bool avx512 = true;
  // solver.threads: threads that step the cloth (the calling one included): the stretch links of
  // a grid of 32 rows or more in blocks (stretch_links.h), prediction and velocity update in
  // ranges of particles. Bit-identical results for every count. 1 by default: a robot's computer
  // runs more than this node, and a spinning worker competes with it (doc/journal.md,
  // "Threads").
  int threads = 1;
  // solver.adaptive_threads: with threads > 1, run a step on the calling thread alone while that is
  // measured to be faster (another process holds a core), trying all threads again now and then
  // (thread_choice.h). The same results either way: the partition of the work does not change.
  bool adaptive_threads = true;
  // solver.search_window: substeps one contact search (particle-particle and self-collision
  // candidates) covers. 0 (the default): chosen per step from the last one's candidates
  // (Collisions, "search window"); k >= 1: every k substeps, a search more wherever a particle
  // leaves its motion bounds; k >= substeps: once per step.
  int search_window = 0;
  // solver.sleep_speed (m/s) and solver.sleep_time (s): when every free particle has moved slower
  // than sleep_speed for sleep_time (stayed within sleep_speed x sleep_time of where it was when
  // that time began), the scene sleeps: steps cost a check instead of a solve until something
  // could move it (Simulation::step, "Sleeping"). 0 = never sleeps (the default,
  // so benchmarks and accuracy tests always solve).
  double sleep_speed = 0.0;
  double sleep_time = 0.5;
};

// What the solver needs of the cloth's material: its compliances (m/N; bending < 0 turns it off)
// and the grid spacing the coarse levels are built for (m).
struct ClothMaterial {
  double stretch_compliance = 0.0;
  double bend_compliance = 1.0e-3;
  double spacing = 0.03;
};

}  // namespace pbd_cloth
