// Accuracy on demand (solver.target_max_strain, solver.target_penetration): the substeps of each
// step chosen within solver.min_substeps .. solver.max_substeps so that the state the simulation
// reports meets the targets at the least cost. A cloth lying still then pays for little, a cloth
// whipped by a gripper for as much as it needs, and the user states an error instead of tuning
// substeps by hand.
//
// The error of a step is the largest of its measured errors over their targets,
//   r = max(max structural strain / target_max_strain, max penetration / target_penetration),
// the strain over the cloth's structural links (links between two kinematic particles left out:
// nothing the solver does moves them), the penetration the deepest into an obstacle, another
// particle or the cloth. Gauss-Seidel's stretch error falls about with the square of the substeps
// (held_corners at 3 s: 9.2 % at 40 x 1, 1.1 % at 120 x 1; doc/journal.md "2026-12-07: Accuracy on
// demand"), so the substeps that bring r to kAim are about n sqrt(r / kAim):
// - r > 1 (over the target): the next step takes n sqrt(r / kAim), at least one more, at most 4 n;
//   and when r > kRedo (far over) the step is run again from its start with those substeps, at
//   most kMaxRedos times: a state published that far over the target would break the user's
//   error bound, and carrying the stretch into the next steps costs them more than one redo.
//   Where the error falls slower than 1 / n^2 (the first step of a cloth let go: 3.6 % at 4
//   substeps, 1.5 % at 30, 1.1 % at 100, 0.17 % at 300) the square-root rule creeps: two redos
//   left such steps at 1.9x the target (doc/journal.md "2026-12-07: Accuracy on demand"). So from
//   the second redo on, the rate is the step's own, measured between its last two attempts,
//   r ~ n^-p with p = log(r_1 / r_2) / log(n_2 / n_1) (clamped to [0.25, 2]; 4 n when the error
//   did not fall), and the substeps are n_2 (r_2 / kAim)^(1/p). Every attempt is bounded by
//   max_substeps, so a step costs at most (kMaxRedos + 1) max_substeps.
// - r < kMargin (well under) for kCalmSteps steps in a row: the next step takes fewer,
//   n sqrt(r / kAim), by at most an eighth a step, so a calm moment does not drop the effort the
//   next jerk needs at once (lowering at once made a swinging cloth cycle: lower, overshoot, run
//   again; doc/journal.md "2026-12-07: Accuracy on demand").
// - else: the same substeps.
// Every decision reads the simulated state alone, never the wall time: the same inputs give the
// same results to the bit, and a data set made with a target can be replayed.
#pragma once

#include "pbd_cloth/solver/solver_settings.h"

namespace pbd_cloth {

class AccuracyController {
 public:
  static constexpr double kAim = 0.75;    // the ratio the substeps are chosen for
  static constexpr double kMargin = 0.5;  // below it, fewer substeps
  static constexpr double kRedo = 1.0;    // above it, the step runs again
  static constexpr int kMaxRedos = 6;
  static constexpr int kCalmSteps = 10;  // steps well under the target before fewer substeps

  // Takes the targets and range; the substeps start at solver.substeps (clamped to the range) on
  // the first configuration and whenever the targets are switched on.
  void configure(const SolverConfig& solver);
  bool active() const { return active_; }
  // Substeps for the next step (or the next attempt of this one).
  int substeps() const { return substeps_; }
  // A restored state's choice and count (saved_state.h), the substeps clamped to the range.
  void restore(int substeps, int calm_steps);
  int calmSteps() const { return calm_steps_; }
  double targetStrain() const { return target_strain_; }
  double targetPenetration() const { return target_penetration_; }
  bool measuresPenetration() const { return target_penetration_ > 0.0; }

  // The step just run with substeps() reached these errors: its ratio to the targets.
  double ratio(double strain, double penetration) const;
  // Whether it should run again from its start, with more substeps (raises substeps()).
  // attempt: how many times this step has already been run again.
  bool redo(double ratio, int attempt);
  // Chooses the next step's substeps after the step's final attempt.
  void update(double ratio);
  // The step's final attempt met the targets (ratio <= 1).
  static bool met(double ratio) { return ratio <= 1.0; }

 private:
  int raised(double ratio) const;
  int raisedAtRate(double ratio) const;

  bool active_ = false;
  double target_strain_ = 0.0;
  double target_penetration_ = 0.0;
  int min_substeps_ = 1;
  int max_substeps_ = 1;
  int substeps_ = 1;
  int calm_steps_ = 0;  // steps in a row with r < kMargin
  // The attempt before the last of the step being run again (redo()): its substeps and ratio.
  int previous_substeps_ = 0;
  double previous_ratio_ = 0.0;
};

}  // namespace pbd_cloth
