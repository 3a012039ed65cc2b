// The solver's configuration, its buffers, and the step in its named phases (the units beside
// this file hold each phase's work).
#include "pbd_cloth/solver/solver.h"

#include <algorithm>
#include <cmath>

#include "pbd_cloth/solver/scoped_timer.h"
#include "pbd_cloth/solver/solver_terms.h"

namespace pbd_cloth {

void Solver::configure(const SolverConfig& solver, const ClothMaterial& cloth) {
  config_ = solver;
  if (pool_.threads() != config_.threads) {
    pool_.resize(config_.threads);
    splitTasks();
    thread_choice_.reset();
  }
  if (!config_.adaptive_threads) thread_choice_.reset();
  pool_.setSolo(thread_choice_.solo());
  stretch_compliance_ = cloth.stretch_compliance;
  bend_compliance_ = cloth.bend_compliance;
  prepared_h_ = kNotPrepared;  // compliances, method or stiffness may have changed
  spacing_ = cloth.spacing;
  // A live change of solver.levels rebuilds them for the grid prepare() saw (not during a step).
  if (coarse_.rows() > 0 &&
      (coarse_.requested() != config_.levels || coarse_.spacing() != spacing_)) {
    coarse_.build(coarse_.rows(), coarse_.cols(), spacing_, config_.levels);
  }
}

void Solver::prepare(const Particles& particles, const ClothTopology& topology) {
  const int n = particles.size();
  prepared_h_ = kNotPrepared;
  stretch_lambda_.assign(topology.stretch.size(), 0.0);
  const bool grid = topology.rows > 0 && !topology.from_mesh;
  stretch_links_.assign(topology.stretch, n, grid ? topology.rows : 0, grid ? topology.cols : 0);
  link_lambda_.assign(topology.stretch.size(), 0.0);
  link_positions_.resize(stretch_links_.size() > 0 ? n : 0);
  column_velocity_.resize(link_positions_.size());
  column_start_.resize(link_positions_.size());
  splitTasks();
  bend_lambda_.assign(topology.bend.size(), Vec3::Zero());
  flat_hinges_.assign(topology.bend_rest.empty() ? topology.bend.size() : 0, FlatHinge());
  jacobi_delta_.assign(n, Vec3::Zero());
  jacobi_count_.assign(n, 0);
  mass_spring_.prepare(n);
  kinematic_velocity_.assign(n, Vec3::Zero());
  kinematic_particles_.clear();
  kinematic_particles_.reserve(n);
  kinematic_stretch_.clear();
  kinematic_stretch_.reserve(topology.stretch.size());
  kinematic_bend_.clear();
  kinematic_bend_.reserve(topology.bend.size());
  reaction_.assign(n, Vec3::Zero());
  start_velocity_.assign(n, Vec3::Zero());
  constraint_force_.assign(n, Vec3::Zero());
  support_force_.assign(n, Vec3::Zero());
  if (topology.rows > 0 && !topology.from_mesh) {
    coarse_.build(topology.rows, topology.cols, spacing_, config_.levels);
  } else {
    coarse_.build(0, 0, 0.0, 0);
  }
}

void Solver::setRopes(std::vector<Rod>* ropes) {
  ropes_ = ropes;
  rope_solvers_.assign(ropes ? ropes->size() : 0, RodSolver());
  for (std::size_t r = 0; r < rope_solvers_.size(); ++r) {
    rope_solvers_[r].prepare((*ropes)[r].segments());
  }
}

void Solver::initializeVelocities(Particles& particles, double dt) const {
  if (config_.method != Method::kVerlet) return;
  // Position Verlet stores the half-step velocity (x_n - x_{n-1}) / h. Starting it at
  // v0 - g h / 2, i.e. x_prev = x0 - v0 h + g h^2 / 2, makes free fall exact (reference case 1).
  const double h = dt / config_.substeps;
  for (int i = 0; i < particles.size(); ++i) {
    if (!particles.isKinematic(i)) particles.velocity[i] -= 0.5 * h * config_.gravity;
  }
}

// alpha~ = alpha / h^2 of the stretch constraints (XPBD eq. 18); PBD and Verlet have none.
double Solver::stretchAlpha(double h) const {
  return config_.method == Method::kXpbd ? stretch_compliance_ / (h * h) : 0.0;
}

// Gauss-Seidel stretch goes through stretch_links_ when they were built for this topology.
// The hinges go through projectFlatBend: Gauss-Seidel, bending on, every hinge flat at rest.
bool Solver::flatBend(const ClothTopology& topology) const {
  return bend_compliance_ >= 0.0 && config_.method != Method::kMassSpring &&
         config_.ordering != Ordering::kJacobi && topology.bend_rest.empty() &&
         flat_hinges_.size() == topology.bend.size();
}

bool Solver::fastStretch(const ClothTopology& topology) const {
  return !topology.stretch.empty() &&
         stretch_links_.size() == static_cast<int>(topology.stretch.size());
}

double Solver::stretchLambda(int c, const ClothTopology& topology) const {
  return config_.ordering != Ordering::kJacobi && fastStretch(topology)
             ? link_lambda_[stretch_links_.position[c]]
             : stretch_lambda_[c];
}

double Solver::pbdStiffness(double k) const {
  // Mueller et al. 2007, sec. 3.3: k' = 1 - (1 - k)^(1/n) makes the stiffness after n passes
  // independent of n (it still depends on dt).
  return 1.0 - std::pow(1.0 - k, 1.0 / config_.iterations);
}

// Velocity kept over a substep by the damping (solver_terms.h, velocityKept).
double Solver::dampingFactor(double h) const { return velocityKept(config_.damping, h); }

// The step of the seeds, phase by phase: prepare, find contacts, then for each substep predict and
// project (or the explicit baseline's substep), update velocities, finish. Each phase's wall time
// adds into its StepStats field.
void Solver::step(double dt, Particles& p, const ClothTopology& topology, Collisions& collisions) {
  const int substeps = config_.substeps;
  const double h = dt / substeps;
  startStepStats();
  {
    ScopedTimer step_timer(stats_.step_wall_time);
    prepareStep(h, p, topology);
    findContacts(dt, p, topology, collisions);
    enterColumns(p, topology, collisions);
    for (int s = 0; s < substeps; ++s) {
      const double s_begin = static_cast<double>(s) / substeps;
      const double s_end = static_cast<double>(s + 1) / substeps;
      collisions.setSubstepFraction(s_begin, s_end);
      if (config_.method == Method::kMassSpring) {
        massSpringSubstep(h, s_end, p, topology, collisions);
        continue;
      }
      predictSubstep(s == 0, h, s_end, p);
      projectSubstep(h, p, topology, collisions);
    }
    finishVelocities(h, p);
    finishStep(dt, h, p, collisions);
  }
  chooseNextThreads();
}

// The stats a step reports start from zero (sim_time adds up over the steps).
void Solver::startStepStats() {
  stats_.substeps = config_.substeps;
  stats_.iterations = 0;
  stats_.predict_time = stats_.collide_time = stats_.project_time = stats_.update_time = 0.0;
  stats_.contact_time = 0.0;
  stats_.step_wall_time = 0.0;
  degenerate_.start();
}

void Solver::prepareStep(double h, Particles& p, const ClothTopology& topology) {
  p.step_start = p.position;
  if (config_.ordering == Ordering::kJacobi) countJacobiConstraints(p, topology);
  // The kinematic set and h are fixed for the step: each link's 1 / (w_i + w_j + alpha~) and each
  // hinge's gains once, and the constraints that join a kinematic to a free particle listed once.
  // They change only with the inverse masses (a grasp, a pin), h or the configuration, so a step
  // like the last one keeps the last one's.
  const bool prepared = h == prepared_h_ && p.inverse_mass == prepared_inverse_mass_;
  startReactions(p, topology, !prepared);
  if (!prepared) {
    if (config_.method != Method::kMassSpring && fastStretch(topology)) {
      stretch_links_.prepareStep(p.inverse_mass.data(), stretchAlpha(h));
    }
    if (bend_compliance_ >= 0.0 && config_.method != Method::kMassSpring) {
      prepareBendStep(p, topology, h);
    }
    prepared_h_ = h;
    prepared_inverse_mass_ = p.inverse_mass;  // same size after the first: no allocation
  }
  coarse_.prepareStep(p);
}

// Find contacts at the step start; every substep enforces them (Jolt's "collide" phase).
// Collisions::project searches again in a substep whose prediction left the swept boxes.
void Solver::findContacts(double dt, Particles& p, const ClothTopology& topology,
                          Collisions& collisions) {
  ScopedTimer timer(stats_.collide_time);
  collisions.setWorkerPool(pool_.threads() > 1 ? &pool_ : nullptr);
  collisions.setSearchWindow(config_.search_window, config_.substeps);
  collisions.beginStep(p, topology, dt);
}

// A step of links alone keeps the particles in columns from its first prediction to its last
// velocity update (linksAlone).
void Solver::enterColumns(const Particles& p, const ClothTopology& topology,
                          const Collisions& collisions) {
  in_columns_ = config_.substeps > 0 && linksAlone(p, topology, collisions);
  stats_.links_in_columns = in_columns_;
  if (in_columns_) stateToColumns(p);
}

// Predict; from the second substep on, fused with the last substep's velocity update.
void Solver::predictSubstep(bool first_substep, double h, double s_end, Particles& p) {
  ScopedTimer timer(stats_.predict_time);
  if (first_substep) {
    predict(h, s_end, p);
  } else {
    updateAndPredict(h, s_end, p);
  }
}

// The explicit baseline: spring and damper forces, then symplectic Euler. Stable only while
// w_max h < 2 (REFERENCE_CASES.md case 8). Contacts are still projected, so the chart compares the
// cloth model, not the collision handling.
void Solver::massSpringSubstep(double h, double s_end, Particles& p, const ClothTopology& topology,
                               Collisions& collisions) {
  {
    ScopedTimer timer(stats_.project_time);
    stats_.iterations += mass_spring_.substep(config_, bend_compliance_, h, s_end, p, topology,
                                              collisions, reaction_, degenerate_);
  }
  ScopedTimer timer(stats_.update_time);
  updateVelocities(h, p);
}

// The last substep's velocity update (the others ran with the next prediction; the explicit
// baseline updates in its own substeps), then the particles leave the columns.
void Solver::finishVelocities(double h, Particles& p) {
  if (config_.method != Method::kMassSpring && config_.substeps > 0) {
    ScopedTimer timer(stats_.update_time);
    updateVelocities(h, p);
  }
  if (in_columns_) {
    stateFromColumns(p);
    in_columns_ = false;
  }
}

void Solver::finishStep(double dt, double h, const Particles& p, Collisions& collisions) {
  finishReactions(dt, h, p, collisions);
  collisions.endStep();
  collisions.setWorkerPool(nullptr);  // lent for the step only
  stats_.sim_time += dt;
  stats_.degenerate_constraints = degenerate_.count;
  stats_.first_degenerate_constraint = degenerate_.first;
}

// The next step's threads, from this step's time (thread_choice.h): the same results either way.
void Solver::chooseNextThreads() {
  stats_.threads_used = pool_.solo() ? 1 : pool_.threads();
  stats_.on_one_thread = pool_.solo() && pool_.threads() > 1;
  if (config_.adaptive_threads && pool_.threads() > 1) {
    pool_.setSolo(thread_choice_.next(stats_.step_wall_time));
  }
}

}  // namespace pbd_cloth
