// The time step of the seeds: predict, find contacts, project constraints (relaxation), update
// velocities. One class serves the four methods (the explicit baseline through its own stepper,
// mass_spring_stepper.h); all buffers are allocated in prepare(), so a step allocates nothing.
// Its units, in src/core/solver/: solver.cpp (configuration and the step's phases), integration
// and prediction_kernels (predict, update velocities), projection_pass, stretch_projection,
// bend_projection, column_layout (a step of links alone), thread_tasks, reactions.
#pragma once

#include <limits>
#include <vector>

#include "pbd_cloth/collision/collisions.h"
#include "pbd_cloth/constraints/coarse_levels.h"
#include "pbd_cloth/constraints/flat_hinges.h"
#include "pbd_cloth/constraints/rod_constraints.h"
#include "pbd_cloth/constraints/stretch_links.h"
#include "pbd_cloth/model/particles.h"
#include "pbd_cloth/parallel/thread_choice.h"
#include "pbd_cloth/parallel/worker_pool.h"
#include "pbd_cloth/solver/mass_spring_stepper.h"
#include "pbd_cloth/solver/solver_settings.h"
#include "pbd_cloth/solver/solver_terms.h"

namespace pbd_cloth {

struct StepStats {
  double sim_time = 0.0;        // s
  double step_wall_time = 0.0;  // s, last step
  int substeps = 0;
  int iterations = 0;  // constraint passes run in the last step, all substeps
  double max_strain = 0.0;
  double mean_strain = 0.0;
  double max_penetration = 0.0;  // m
  // Time per phase of the last step (s): predict, collide (broad phase), project, update.
  double predict_time = 0.0;
  double collide_time = 0.0;
  double project_time = 0.0;
  double update_time = 0.0;
  // Of project_time: the contact projections (particle-particle, self-collision, obstacles,
  // bounds, with friction), i.e. the collisions' narrow phase.
  double contact_time = 0.0;
  // Stretch constraints skipped in the last pass of the step because their particles coincide
  // (no direction to correct along), and the index of the first of them (-1: none).
  int degenerate_constraints = 0;
  int first_degenerate_constraint = -1;
  // Threads that ran the last step: solver.threads, or 1 where solver.adaptive_threads chose the
  // calling thread alone (thread_choice.h); 0 for a step slept through (no solve).
  int threads_used = 1;
  // The last step ran on the calling thread alone although solver.threads > 1 (what the node's
  // diagnostics and cloth_bench's solo_steps count).
  bool on_one_thread = false;
  // The last step was one of links alone (Solver::linksAlone: nothing but the flat links and the
  // coarse levels in a pass) and kept the particles in columns from its first prediction to its
  // last velocity update; the same result to the bit as the passes in place.
  bool links_in_columns = false;
};

class Solver {
 public:
  void configure(const SolverConfig& solver, const ClothMaterial& cloth);
  const SolverConfig& config() const { return config_; }
  // The substeps of the next step (the accuracy controller's choice, sim/accuracy_controller.h);
  // the rest of the configuration stays.
  void setSubsteps(int substeps) { config_.substeps = substeps; }
  // Sizes every buffer for these particles and constraints; call after the topology changes.
  void prepare(const Particles& particles, const ClothTopology& topology);
  // The scene's ropes (Cosserat rods, model/rod.h), solved in every pass after the cloth's own
  // constraints and before the contacts, on their particles among `p`; nullptr or empty: none.
  // Sizes their solvers' room (outside the step).
  void setRopes(std::vector<Rod>* ropes);
  // Gives Verlet its exact start (x_prev = x0 - v0 h + g h^2 / 2, REFERENCE_CASES.md case 1).
  void initializeVelocities(Particles& particles, double dt) const;

  // Advances the particles by dt. Kinematic particles move from kinematic_from to kinematic_to,
  // interpolated across substeps.
  void step(double dt, Particles& particles, const ClothTopology& topology, Collisions& collisions);

  const StepStats& stats() const { return stats_; }
  StepStats& mutableStats() { return stats_; }
  // The force every constraint and contact exerted on each kinematic particle over the last step,
  // i.e. its impulse divided by dt (N; zero for free particles): stretch, bending, tethers,
  // particle-particle and self-contacts, in every method. A kinematic particle is not moved by
  // them, so each projection's reaction on it (its gradient times the multiplier, the momentum
  // the free particles of the constraint received, reversed) is summed instead.
  const Vec3Array& constraintForce() const { return constraint_force_; }
  // The force each kinematic particle exerted on what moves it (its pin or gripper) over the last
  // step (N): the constraint force, plus its own weight, minus its mass times its acceleration
  // (the change of its prescribed velocity over the step, divided by dt).
  const Vec3Array& supportForce() const { return support_force_; }

 private:
  void predict(double h, double s_end, Particles& p);
  void updateAndPredict(double h, double s_end, Particles& p);
  // The free particles' update (of the substep ending), prediction (of the substep to s_end), or
  // both in one pass; kinematic particles take their prescribed motion.
  void advance(double h, double s_end, bool update, bool predict, Particles& p);
  // first_pass: the substep's first, whose multipliers start at zero; last_pass: its last by the
  // count (solver.iterations), after which only the kinematic reactions read multipliers.
  double projectPass(double h, Particles& p, const ClothTopology& topology, Collisions& collisions,
                     bool first_pass, bool last_pass);
  double projectStretch(double h, Particles& p, const ClothTopology& topology, bool first_pass);
  double projectBend(double h, Particles& p, const ClothTopology& topology, bool first_pass,
                     bool last_pass);
  double projectFlatBend(Particles& p, const ClothTopology& topology, bool first_pass,
                         bool last_pass);
  bool flatBend(const ClothTopology& topology) const;
  void prepareBendStep(const Particles& p, const ClothTopology& topology, double h);
  double projectTethers(Particles& p, const ClothTopology& topology);
  double projectRopes(double h, Particles& p, bool first_pass);
  bool hasRopes() const { return ropes_ != nullptr && !ropes_->empty(); }
  void applyJacobi(Particles& p, double& max_change);
  void updateVelocities(double h, Particles& p);
  // The phases of step(), in its order.
  void startStepStats();
  void prepareStep(double h, Particles& p, const ClothTopology& topology);
  void findContacts(double dt, Particles& p, const ClothTopology& topology, Collisions& collisions);
  void enterColumns(const Particles& p, const ClothTopology& topology,
                    const Collisions& collisions);
  void predictSubstep(bool first_substep, double h, double s_end, Particles& p);
  void projectSubstep(double h, Particles& p, const ClothTopology& topology,
                      Collisions& collisions);
  void massSpringSubstep(double h, double s_end, Particles& p, const ClothTopology& topology,
                         Collisions& collisions);
  void finishVelocities(double h, Particles& p);
  void finishStep(double dt, double h, const Particles& p, Collisions& collisions);
  void chooseNextThreads();
  double pbdStiffness(double k) const;
  double stretchAlpha(double h) const;
  double dampingFactor(double h) const;
  // Whether a pass measures its largest correction: only solver.tolerance (adaptive pass counts)
  // reads it, so without a tolerance the links, levels and hinges leave it out.
  bool tracksLargestChange() const { return config_.tolerance > 0.0; }
  void countJacobiConstraints(const Particles& p, const ClothTopology& topology);
  void startReactions(const Particles& p, const ClothTopology& topology, bool list);
  void addMultiplierReactions(const Particles& p, const ClothTopology& topology);
  void finishReactions(double dt, double h, const Particles& p, const Collisions& collisions);
  double jacobiScale(int i, int j) const;

  SolverConfig config_;
  double stretch_compliance_ = 0.0;
  double bend_compliance_ = -1.0;
  double spacing_ = 0.0;                 // cloth.spacing: the rest geometry of the coarse levels
  CoarseLevels coarse_;                  // solver.levels; empty when off or the cloth is a mesh
  std::vector<double> stretch_lambda_;   // XPBD multipliers, reset every substep
  std::vector<Rod>* ropes_ = nullptr;    // the Simulation's, or nullptr
  std::vector<RodSolver> rope_solvers_;  // one per rope
  StretchLinks stretch_links_;           // topology.stretch in flat arrays and batches (prepare)
  std::vector<double> link_lambda_;      // their multipliers in stretch_links_' order
  ColumnPositions link_positions_;       // the particles' positions in columns during the sweep
  // A step of links alone (linksAlone): the particles' velocities and substep starts in columns
  // beside link_positions_, which then hold the positions from the step's first prediction to its
  // last velocity update instead of being filled and emptied around every sweep.
  ColumnPositions column_velocity_;
  ColumnPositions column_start_;
  bool in_columns_ = false;  // this step runs in the columns
  bool linksAlone(const Particles& p, const ClothTopology& topology,
                  const Collisions& collisions) const;
  void stateToColumns(const Particles& p);
  void stateFromColumns(Particles& p);
  // solver.threads: the workers, and each thread's tasks of each phase of the links (a range of
  // stretch_links_' tasks, balanced by link count): thread t of phase p runs tasks
  // [thread_tasks_[p * (T + 1) + t], thread_tasks_[p * (T + 1) + t + 1]).
  WorkerPool pool_;
  ThreadChoice thread_choice_;  // solver.adaptive_threads: pool_ solo or not, step by step
  std::vector<int> thread_tasks_;
  std::vector<StretchPassResult> thread_results_;
  void splitTasks();
  bool fastStretch(const ClothTopology& topology) const;
  double stretchLambda(int c, const ClothTopology& topology) const;
  Vec3Array bend_lambda_;  // one vector per hinge: C = scale b is vector-valued
  // Per step (prepareBendStep): what the step fixes for each hinge of a flat rest shape
  // (flat_hinges.h); empty for hinges with a rest curvature (mesh cloths).
  std::vector<FlatHinge> flat_hinges_;
  // What the step preparations (the links' and hinges' per-step terms, the kinematic lists) were
  // made for: they stand while h and the inverse masses are the same. NaN: to be made.
  static constexpr double kNotPrepared = std::numeric_limits<double>::quiet_NaN();
  double prepared_h_ = kNotPrepared;
  std::vector<double> prepared_inverse_mass_;
  Vec3Array jacobi_delta_;         // Jacobi: summed corrections per particle
  std::vector<int> jacobi_count_;  // Jacobi: stretch and bend constraints on each free particle
  MassSpringStepper mass_spring_;  // solver.method mass_spring: the explicit baseline
  std::vector<int> kinematic_particles_;  // the step's kinematic particles (startReactions)
  Vec3Array kinematic_velocity_;          // a kinematic particle's velocity kept across predict()
  // Reactions on kinematic particles: the stretch constraints and hinges with a kinematic and a
  // free particle (listed once per step), the sum of gradient times multiplier over the step
  // (kg m), the velocities at the step start, and the two forces of the last step.
  std::vector<int> kinematic_stretch_;
  std::vector<int> kinematic_bend_;
  Vec3Array reaction_;
  Vec3Array start_velocity_;
  Vec3Array constraint_force_;
  Vec3Array support_force_;
  StepStats stats_;
  DegenerateCount degenerate_;  // in the current pass; the last pass's become the step's stats
};

}  // namespace pbd_cloth
