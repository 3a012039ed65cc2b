#include "pbd_cloth/solver/solver.h"

#include <algorithm>
#include <cmath>

#include "pbd_cloth/constraints/flat_hinges.h"
#include "pbd_cloth/constraints/tether_projection.h"
#include "pbd_cloth/solver/scoped_timer.h"

namespace pbd_cloth {

namespace {

// Below this length a distance constraint has no direction: skipped (coincident particles).
constexpr double kMinLength = 1e-12;
// Below this a constraint's generalized inverse mass is zero (all particles kinematic): skipped.
constexpr double kMinInverseMass = 1e-300;
// The stretch links read positions as one flat array x0 y0 z0 x1 ... (stretch_links.h).
static_assert(sizeof(Vec3) == 3 * sizeof(double), "Vec3Array must be densely packed");

// The mean-curvature vector b = sum_k K_k x_k of a hinge, computed as sum_{k>0} K_k (x_k - x_0)
// (the weights sum to zero): the same value, without the cancellation of large coordinates that
// would leave ~1e-12 m of noise in a flat hinge 1e4 m from the origin.
Vec3 bendVector(const BendConstraint& con, const Particles& p) {
  const Vec3& x0 = p.position[con.index[0]];
  return con.weight[1] * (p.position[con.index[1]] - x0) +
         con.weight[2] * (p.position[con.index[2]] - x0) +
         con.weight[3] * (p.position[con.index[3]] - x0);
}

// The rest bending vector of a curved mesh hinge carried into the current positions: b0 = sum of
// its components along each triangle's current frame (edge, in-plane normal, normal), averaged
// over the two triangles so neither is preferred. Treated as fixed within one projection (its
// dependence on the positions is left out of the gradient): the constraint stays linear with the
// vector multiplier of the flat model, and at the rest shape, in any pose, b = b0' exactly.
Vec3 restBendVector(const BendConstraint& con, const BendRest& rest, const Particles& p) {
  const Vec3& x0 = p.position[con.index[0]];
  const Vec3 edge = p.position[con.index[1]] - x0;
  const double length = edge.norm();
  if (!(length > kMinLength)) return Vec3::Zero();
  const Vec3 t = edge / length;
  Vec3 target = Vec3::Zero();
  for (int side = 0; side < 2; ++side) {
    Vec3 n = t.cross(p.position[con.index[2 + side]] - x0);
    const double norm = n.norm();
    if (!(norm > kMinLength * length)) continue;  // collapsed triangle: no frame this time
    n /= side == 0 ? norm : -norm;
    const Vec3& c = side == 0 ? rest.in_first : rest.in_second;
    target += 0.5 * (c.x() * t + c.y() * n.cross(t) + c.z() * n);
  }
  return target;
}

}  // namespace

void Solver::configure(const SolverConfig& solver, const ClothConfig& cloth) {
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
  sizeChebyshevBuffers();  // solver.chebyshev may have been switched on or off
}

// One position a particle for each buffer while solver.chebyshev is on (force_ has the particle
// count prepare() saw); released while it is off.
void Solver::sizeChebyshevBuffers() {
  if (config_.chebyshev > 0.0) {
    chebyshev_current_.assign(force_.size(), Vec3::Zero());
    chebyshev_previous_.assign(force_.size(), Vec3::Zero());
  } else {
    Vec3Array().swap(chebyshev_current_);
    Vec3Array().swap(chebyshev_previous_);
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
  force_.assign(n, Vec3::Zero());
  sizeChebyshevBuffers();
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

// Each phase's tasks cut into solver.threads contiguous ranges of about equal link counts. Which
// thread runs which task changes nothing in the result (the tasks of a phase are independent).
void Solver::splitTasks() {
  const int threads = pool_.threads();
  thread_results_.assign(threads, StretchPassResult());
  thread_tasks_.clear();
  for (int phase = 0; phase < stretch_links_.phaseCount(); ++phase) {
    const int first = stretch_links_.phase_task[phase], end = stretch_links_.phase_task[phase + 1];
    long total = 0;
    for (int t = first; t < end; ++t) total += stretch_links_.taskLinks(t);
    thread_tasks_.push_back(first);
    long done = 0;
    int task = first;
    for (int t = 1; t < threads; ++t) {
      // Thread t - 1 takes tasks until its share of the links (t / threads of the total) is met.
      // A task goes to this thread when its middle lies within the thread's share.
      while (task < end && (2 * done + stretch_links_.taskLinks(task)) * threads <= 2 * t * total) {
        done += stretch_links_.taskLinks(task);
        ++task;
      }
      thread_tasks_.push_back(task);
    }
    thread_tasks_.push_back(end);
  }
}

double Solver::pbdStiffness(double k) const {
  // Mueller et al. 2007, sec. 3.3: k' = 1 - (1 - k)^(1/n) makes the stiffness after n passes
  // independent of n (it still depends on dt).
  return 1.0 - std::pow(1.0 - k, 1.0 / config_.iterations);
}

// Velocity kept over a substep by the damping dv/dt = -c v, integrated exactly: e^{-c h}. Unlike
// 1 - c h it never turns negative and is the same for any split of a step into substeps.
double Solver::dampingFactor(double h) const { return std::exp(-config_.damping * h); }

namespace {

#if defined(__GNUC__)
#define PBD_INLINE inline __attribute__((always_inline))
#else
#define PBD_INLINE inline
#endif
struct PredictArgs {
  int begin = 0, end = 0;  // particles
  double keep = 1.0, h = 0.0, inv_h = 0.0, dv_x = 0.0, dv_y = 0.0, dv_z = 0.0;
  double *x = nullptr, *v = nullptr, *start = nullptr;  // flat coordinates
};

// One coordinate k of a particle: the prediction x~ = x + h (e^{-c h} v + h g) of a substep, and
// the velocity update v <- v + (x - x~) / h that ends it (why in that form: Solver::
// updateVelocities). The update needs no stored x~: while a substep runs nothing writes v or the
// substep's start, so start + h v is the prediction again, to the bit (the same operands and
// operation as x += h v).
PBD_INLINE void predictCoordinate(int k, double dv, const PredictArgs& a, double* __restrict x,
                                  double* __restrict v, double* __restrict start) {
  start[k] = x[k];
  v[k] = a.keep * v[k] + dv;
  x[k] += a.h * v[k];
}

PBD_INLINE void updateCoordinate(int k, const PredictArgs& a, const double* __restrict x,
                                 double* __restrict v, const double* __restrict start) {
  v[k] += (x[k] - (start[k] + a.h * v[k])) * a.inv_h;
}

// Over particles [begin, end), four (twelve coordinates, three AVX2 registers) at a time, the
// rest one by one: one loop with no branch over distinct arrays (restrict), straight vector code.
// `update` ends the last substep first, `predict` starts the next: both in one pass over the
// arrays (Solver::updateAndPredict) read and write each coordinate once instead of twice.
template <bool update, bool predict>
PBD_INLINE void advanceFree(const PredictArgs& a) {
  double* __restrict x = a.x;
  double* __restrict v = a.v;
  double* __restrict start = a.start;
  const double dv[12] = {a.dv_x, a.dv_y, a.dv_z, a.dv_x, a.dv_y, a.dv_z,
                         a.dv_x, a.dv_y, a.dv_z, a.dv_x, a.dv_y, a.dv_z};
  auto advance = [&](int k, int q) {
    if (update) updateCoordinate(k, a, x, v, start);
    if (predict) predictCoordinate(k, dv[q], a, x, v, start);
  };
  int i = a.begin;
  for (; i + 4 <= a.end; i += 4) {
    for (int q = 0; q < 12; ++q) advance(3 * i + q, q);
  }
  for (; i < a.end; ++i) {
    for (int d = 0; d < 3; ++d) advance(3 * i + d, d);
  }
}

// The same on the particles' columns (Solver::advance in a step of links alone): x, v and
// start each hold the x column, then the y and the z column, `stride` apart; the same operations
// on each coordinate, so the same result to the bit.
template <bool update, bool predict>
PBD_INLINE void advanceFreeColumns(const PredictArgs& a, int stride) {
  double* __restrict x = a.x;
  double* __restrict v = a.v;
  double* __restrict start = a.start;
  const double dv[3] = {a.dv_x, a.dv_y, a.dv_z};
  for (int d = 0; d < 3; ++d) {
    const int end = d * stride + a.end;
    for (int k = d * stride + a.begin; k < end; ++k) {
      if (update) updateCoordinate(k, a, x, v, start);
      if (predict) predictCoordinate(k, dv[d], a, x, v, start);
    }
  }
}

// Every particle's prediction, update, or both, as if it were free (seed: v += h g, x += h v;
// XPBD Algorithm 1, lines 3-4 and 11). Solver::predict and Solver::updateVelocities then put the
// kinematic particles right. The body is inlined into two builds, AVX2 and the baseline, chosen
// at run time as the stretch links' (stretch_links.h; not function multiversioning, whose
// load-time resolvers the sanitizer builds cannot run); no FMA in either, so both round alike.
#if defined(__x86_64__) && defined(__GNUC__)
template <bool update, bool predict>
__attribute__((target("avx2"))) void advanceFreeAvx2(const PredictArgs& a) {
  advanceFree<update, predict>(a);
}

template <bool update, bool predict>
__attribute__((target("avx2"))) void advanceFreeColumnsAvx2(const PredictArgs& a, int stride) {
  advanceFreeColumns<update, predict>(a, stride);
}
#endif

template <bool update, bool predict>
void advanceFree(const PredictArgs& a, bool avx2) {
#if defined(__x86_64__) && defined(__GNUC__)
  if (avx2) return advanceFreeAvx2<update, predict>(a);
#else
  (void)avx2;
#endif
  advanceFree<update, predict>(a);
}

template <bool update, bool predict>
void advanceFreeColumns(const PredictArgs& a, int stride, bool avx2) {
#if defined(__x86_64__) && defined(__GNUC__)
  if (avx2) return advanceFreeColumnsAvx2<update, predict>(a, stride);
#else
  (void)avx2;
#endif
  advanceFreeColumns<update, predict>(a, stride);
}

// Calls advanceFree<update, predict> (interleaved) or advanceFreeColumns with the flags as values.
void advanceFreeRange(const PredictArgs& a, bool update, bool predict, int column_stride,
                      bool avx2) {
  const bool columns = column_stride > 0;
  if (update && predict) {
    columns ? advanceFreeColumns<true, true>(a, column_stride, avx2)
            : advanceFree<true, true>(a, avx2);
  } else if (update) {
    columns ? advanceFreeColumns<true, false>(a, column_stride, avx2)
            : advanceFree<true, false>(a, avx2);
  } else {
    columns ? advanceFreeColumns<false, true>(a, column_stride, avx2)
            : advanceFree<false, true>(a, avx2);
  }
}

}  // namespace

// Predict (seed: Verlet step; PBD: symplectic Euler): damp the carried velocity, v = e^{-c h} v +
// h g, x += h v. Damping acts on the velocity the particle carries, not on this substep's gravity
// increment: a body at rest feels the full g h^2 and a damped link settles at the undamped static
// stretch (a viscous damper exerts no force at rest; REFERENCE_CASES.md case 6). Kinematic
// particles take their prescribed position at fraction s_end of the step instead.
void Solver::predict(double h, double s_end, Particles& p) { advance(h, s_end, false, true, p); }

// The velocity update of a substep and the prediction of the next, in one pass over the particles
// (each coordinate read and written once, not twice): the same operations in the same order as
// updateVelocities then predict, so the same result to the bit.
void Solver::updateAndPredict(double h, double s_end, Particles& p) {
  advance(h, s_end, true, true, p);
}

void Solver::advance(double h, double s_end, bool update, bool predict, Particles& p) {
  const int n = p.size();
  if (n == 0) return;
  const Vec3 dv = h * config_.gravity;
  PredictArgs args;
  args.keep = dampingFactor(h);
  args.h = h;
  args.inv_h = 1.0 / h;
  args.dv_x = dv[0];
  args.dv_y = dv[1];
  args.dv_z = dv[2];
  // Interleaved (x0 y0 z0 x1 ...) in `p`, or in columns during a step of links alone: coordinate
  // d of particle i is at i * particle_step + d * coordinate_step either way.
  const bool columns = in_columns_;
  args.x = columns ? link_positions_.columns().x : p.position.front().data();
  args.v = columns ? column_velocity_.columns().x : p.velocity.front().data();
  args.start = columns ? column_start_.columns().x : p.substep_start.front().data();
  const int particle_step = columns ? 1 : 3;
  const int coordinate_step = columns ? link_positions_.size() : 1;
  const bool avx2 = config_.simd && stretchLinksUseAvx2();
  // Threads take equal ranges of particles (each particle on its own).
  pool_.runRanges(n, [&](int begin, int end, int) {
    // A kinematic particle's velocity is the one it moved with over the substep, (x - x_start) /
    // h; a prediction keeps it (the free particles' arithmetic runs on it too, and is undone).
    for (int i : kinematic_particles_) {
      if (i < begin || i >= end) continue;
      for (int d = 0; d < 3; ++d) {
        const int k = i * particle_step + d * coordinate_step;
        kinematic_velocity_[i][d] = update ? (args.x[k] - args.start[k]) * args.inv_h : args.v[k];
      }
    }
    PredictArgs range = args;
    range.begin = begin;
    range.end = end;
    advanceFreeRange(range, update, predict, columns ? coordinate_step : 0, avx2);
    for (int i : kinematic_particles_) {
      if (i < begin || i >= end) continue;
      for (int d = 0; d < 3; ++d) {
        const int k = i * particle_step + d * coordinate_step;
        args.v[k] = kinematic_velocity_[i][d];
        if (predict) {
          args.x[k] = (1.0 - s_end) * p.kinematic_from[i][d] + s_end * p.kinematic_to[i][d];
        }
      }
    }
  });
}

// A step of links alone: nothing in a pass but the coarse levels and the flat links (no hinges,
// tethers or Chebyshev, and collisions that touch no particle: a cloth swinging free), Gauss-
// Seidel. Its positions, velocities and substep starts then stay in columns for the whole step
// (stateToColumns before the first prediction, stateFromColumns after the last update), where
// otherwise every pass copies the positions into the columns and back around the sweep: 13.5 % of
// the 100 x 100 swinging cloth's step (doc/performance.md, "A step of links alone, in columns").
bool Solver::linksAlone(const Particles& p, const ClothTopology& topology,
                        const Collisions& collisions) const {
  return config_.method != Method::kMassSpring && config_.ordering != Ordering::kJacobi &&
         fastStretch(topology) && link_positions_.size() == p.size() && bend_compliance_ < 0.0 &&
         topology.tethers.empty() && config_.chebyshev == 0.0 &&
         (coarse_.levelCount() == 0 || !config_.levels_interpolate) &&
         collisions.touchesNoParticle(p, topology);
}

void Solver::stateToColumns(const Particles& p) {
  const int n = p.size();
  positionsToColumns(p.position.front().data(), 0, n, link_positions_.columns(), config_.simd);
  positionsToColumns(p.velocity.front().data(), 0, n, column_velocity_.columns(), config_.simd);
}

void Solver::stateFromColumns(Particles& p) {
  const int n = p.size();
  positionsFromColumns(link_positions_.columns(), 0, n, p.position.front().data(), config_.simd);
  positionsFromColumns(column_velocity_.columns(), 0, n, p.velocity.front().data(), config_.simd);
  positionsFromColumns(column_start_.columns(), 0, n, p.substep_start.front().data(), config_.simd);
}

// Jacobi with averaging scales constraint c's multiplier step by w / max_k n_k over its free
// particles k (n_k = number of constraints on particle k, w = solver.relaxation). This is the
// averaging of Bender et al. 2017, eq. 48 (dx_i = w / n_i sum_c dx_i^c) applied per constraint
// instead of per particle: both ends get the same scaled step and lambda accumulates exactly what
// was applied, so momentum is conserved and the fixed point is the XPBD solution
// x - x~ = M^-1 grad C^T lambda, C + alpha~ lambda = 0. Per-particle averaging moves a particle
// with n_i constraints as if its mass were n_i / w times larger, and an XPBD chain then settles at
// n_i / w times the stretch alpha T (REFERENCE_CASES.md case 6). For one particle under K
// constraints the two are the same: x <- (1 - w) d (case 7). For distance constraints (unit
// gradients) it converges for 0 < w < 2: linearized, the scaled step is a Richardson iteration on
// (J M^-1 J^T + alpha~) lambda = -C with the diagonal preconditioner D = (w_i + w_j + alpha~) max n
// / w, and 2D - A is diagonally dominant (Gershgorin), hence positive definite.
double Solver::jacobiScale(int i, int j) const {
  return config_.relaxation / std::max({1, jacobi_count_[i], jacobi_count_[j]});
}

// Stretch constraints C = |x_i - x_j| - l0 (seed eq. C2). verlet: rigid projection weighted by
// inverse mass (the seed's stick, x1 -= w1/(w1+w2) C n); pbd: the same scaled by k';
// xpbd: dlambda = (-C - alpha~ lambda) / (w_i + w_j + alpha~), alpha~ = alpha / h^2 (XPBD eq. 18).
double Solver::projectStretch(double h, Particles& p, const ClothTopology& topology,
                              bool first_pass) {
  const bool xpbd = config_.method == Method::kXpbd;
  const bool jacobi = config_.ordering == Ordering::kJacobi;
  const bool average = jacobi && config_.jacobi_averaging;
  const double alpha = stretchAlpha(h);
  const double k = config_.method == Method::kPbd ? pbdStiffness(config_.stretch_stiffness) : 1.0;
  const int count = static_cast<int>(topology.stretch.size());
  if (!jacobi && fastStretch(topology)) {
    // Gauss-Seidel: the flat, batched links (stretch_links.h), phase by phase; the tasks of a
    // phase share no particle, so threads run them side by side with the sequential result.
    StretchProjection how;
    how.alpha = alpha;
    how.stiffness = k;
    how.simd = config_.simd;
    how.avx512 = config_.avx512;
    how.track_change = tracksLargestChange();
    how.lambda_from_zero = first_pass;
    // The sweep works on the positions in columns (stretch_links.h, PositionColumns): copied in
    // and back out around it, which costs a small part of what the columns save the sweep. The
    // copies run on this thread: with solver.threads 2 one more meeting of the threads for each
    // cost more than the half copy it saved (doc/performance.md, "Positions in columns").
    // In a step of links alone they are there already (linksAlone).
    double* x = p.position.front().data();
    const PositionColumns columns = link_positions_.columns();
    if (!in_columns_) positionsToColumns(x, 0, p.size(), columns, config_.simd);
    StretchPassResult result;
    const int threads = pool_.threads();
    for (int phase = 0; phase < stretch_links_.phaseCount(); ++phase) {
      const int* range = &thread_tasks_[phase * (threads + 1)];
      auto job = [&](int t) {
        thread_results_[t] = projectStretchLinks(
            stretch_links_, stretch_links_.task_batch[range[t]],
            stretch_links_.task_batch[range[t + 1]], how, columns, link_lambda_.data());
      };
      pool_.run(job);
      for (int t = 0; t < threads; ++t) result.merge(thread_results_[t]);
    }
    if (!in_columns_) positionsFromColumns(columns, 0, p.size(), x, config_.simd);
    if (result.degenerate > 0) {
      if (degenerate_in_pass_ == 0) {
        first_degenerate_in_pass_ = stretch_links_.original[result.first_degenerate];
      }
      degenerate_in_pass_ += result.degenerate;
    }
    return result.max_change;
  }
  double max_change = 0.0;
  for (int c = 0; c < count; ++c) {
    const DistanceConstraint& con = topology.stretch[c];
    const double wi = p.inverse_mass[con.i], wj = p.inverse_mass[con.j];
    const double w = wi + wj;
    if (w < kMinInverseMass) continue;
    const Vec3 delta = p.position[con.i] - p.position[con.j];
    const double length = delta.norm();
    if (length < kMinLength) {
      // Coincident particles: no direction to push along. Skipped for this pass (the other
      // constraints pull them apart) and reported, so it does not pass silently.
      noteDegenerate(c);
      continue;
    }
    const Vec3 n = delta / length;
    const double constraint = length - con.rest_length;
    double dlambda =
        xpbd ? (-constraint - alpha * stretch_lambda_[c]) / (w + alpha) : -k * constraint / w;
    if (average) dlambda *= jacobiScale(con.i, con.j);
    stretch_lambda_[c] += dlambda;
    const Vec3 correction = dlambda * n;
    max_change = std::max(max_change, std::abs(dlambda) * std::max(wi, wj));
    if (jacobi) {
      jacobi_delta_[con.i] += wi * correction;
      jacobi_delta_[con.j] -= wj * correction;
    } else {
      p.position[con.i] += wi * correction;
      p.position[con.j] -= wj * correction;
    }
  }
  return max_change;
}

// Isometric bending as the vector constraint C = scale b, b = sum_k K_k x_k (particles.h): linear
// in the positions, grad_k C = scale K_k I. A flat hinge (b = 0) gets no correction; nothing is
// divided by |b|, so there is no degenerate case.
double Solver::projectBend(double h, Particles& p, const ClothTopology& topology, bool first_pass,
                           bool last_pass) {
  if (bend_compliance_ < 0.0 || config_.method == Method::kMassSpring) return 0.0;
  const bool xpbd = config_.method == Method::kXpbd;
  const bool jacobi = config_.ordering == Ordering::kJacobi;
  const bool average = jacobi && config_.jacobi_averaging;
  const double alpha = xpbd ? bend_compliance_ / (h * h) : 0.0;
  const double k = xpbd ? 1.0 : pbdStiffness(config_.bend_stiffness);
  double max_change = 0.0;
  const int count = static_cast<int>(topology.bend.size());
  if (flatBend(topology)) return projectFlatBend(p, topology, first_pass, last_pass);
  const bool has_rest = !topology.bend_rest.empty();
  for (int c = 0; c < count; ++c) {
    const BendConstraint& con = topology.bend[c];
    double w = 0.0;
    for (int v = 0; v < 4; ++v) {
      w += p.inverse_mass[con.index[v]] * con.weight[v] * con.weight[v];
    }
    w *= con.scale * con.scale;
    if (w < kMinInverseMass) continue;
    // The vector constraint C = scale b (three rows, each with gradient scale K_k per vertex) has
    // the same energy as scale |b| but is linear in the positions: one projection solves it
    // exactly, and the multiplier is a vector, so a hinge that swings through flat keeps the
    // direction of its accumulated force instead of flipping the sign of a scalar lambda, and no
    // |b| is divided by. XPBD: dlambda = (-C - alpha lambda) / (w + alpha) (Macklin et al. 2016,
    // eq. 18), row by row with the common w.
    // Mesh hinges with a curved rest shape: C = scale (b - b0'), b0' the rest vector in the
    // hinge's current frames (restBendVector); flat hinges and the grid: C = scale b.
    const Vec3 constraint =
        has_rest && topology.bend_rest[c].curved
            ? Vec3(con.scale * (bendVector(con, p) - restBendVector(con, topology.bend_rest[c], p)))
            : Vec3(con.scale * bendVector(con, p));
    Vec3 dlambda = xpbd ? Vec3((-constraint - alpha * bend_lambda_[c]) / (w + alpha))
                        : Vec3((-k / w) * constraint);
    if (average) {
      dlambda *= std::min(jacobiScale(con.index[0], con.index[1]),
                          jacobiScale(con.index[2], con.index[3]));
    }
    bend_lambda_[c] += dlambda;
    const Vec3 direction = con.scale * dlambda;
    // |dx_k| = w_k |K_k| |direction|: one norm per hinge, not per vertex.
    double largest_weight = 0.0;
    for (int v = 0; v < 4; ++v) {
      const int i = con.index[v];
      const double factor = p.inverse_mass[i] * con.weight[v];
      largest_weight = std::max(largest_weight, std::abs(factor));
      if (jacobi) {
        jacobi_delta_[i] += factor * direction;
      } else {
        p.position[i] += factor * direction;
      }
    }
    max_change = std::max(max_change, largest_weight * direction.norm());
  }
  return max_change;
}

// The hinges of a flat rest shape (every grid hinge) in Gauss-Seidel order, with what is fixed
// for a step computed once in prepareBendStep (flat_hinges.h): the same projection as the loop of
// projectBend, with no division and no per-vertex weight arithmetic in the pass.
double Solver::projectFlatBend(Particles& p, const ClothTopology& topology, bool first_pass,
                               bool last_pass) {
  if (topology.bend.empty()) return 0.0;  // (and no multipliers to point at)
  double* x = p.position.front().data();
  const bool track_change = tracksLargestChange();
  // Hinges [begin, end) in order.
  auto sweep = [&](int begin, int end) {
    return projectFlatHinges(flat_hinges_.data() + begin, end - begin, first_pass, !last_pass,
                             track_change, config_.simd, config_.avx512, x,
                             bend_lambda_.front().data() + 3 * static_cast<std::size_t>(begin));
  };
  const int threads = pool_.threads();
  const std::vector<int>& task = topology.bend_task;
  if (threads == 1 || task.empty()) return sweep(0, static_cast<int>(topology.bend.size()));
  // The blocks' tasks, then the seams' (cloth_builder.cpp, groupHingesIntoTasks): each thread
  // a consecutive range of a group's tasks, in the order one thread runs them all.
  double max_change = 0.0;
  const int groups[3] = {0, topology.bend_blocks, static_cast<int>(task.size()) - 1};
  for (int g = 0; g < 2; ++g) {
    const int tasks = groups[g + 1] - groups[g];
    pool_.runRanges(tasks, [&](int first, int last, int t) {
      thread_results_[t].max_change = sweep(task[groups[g] + first], task[groups[g] + last]);
    });
    for (int t = 0; t < threads; ++t) {
      max_change = std::max(max_change, thread_results_[t].max_change);
    }
  }
  return max_change;
}

// XPBD's dlambda = (-k C - alpha~ lambda) / (w + alpha~) for C = scale b (eq. 18), split into
// what the step fixes: gain_k = -k scale K_k / (w + alpha~) and decay = alpha~ / (w + alpha~);
// corner k moves by w_k K_k scale dlambda (flat_hinges.h).
void Solver::prepareBendStep(const Particles& p, const ClothTopology& topology, double h) {
  const int count = static_cast<int>(topology.bend.size());
  if (static_cast<int>(flat_hinges_.size()) != count) return;
  const bool xpbd = config_.method == Method::kXpbd;
  const double alpha = xpbd ? bend_compliance_ / (h * h) : 0.0;
  const double k = xpbd ? 1.0 : pbdStiffness(config_.bend_stiffness);
  for (int c = 0; c < count; ++c) {
    flat_hinges_[c] =
        makeFlatHinge(topology.bend[c], p.inverse_mass.data(), alpha, k, kMinInverseMass);
  }
}

// Long-range attachments (Kim et al. 2012): unilateral, only the free particle moves, so a
// tether never fights the anchor. A particle with several anchors must end inside the
// intersection of their balls, and projecting onto one ball can push it out of another: its
// tethers (contiguous in the list) are solved together, by rounds of a two-constraint active set:
// a = the most violated tether; if the projection into a's ball violates another, b = the worst of
// those, and the particle goes to the nearest point of the lens of a and b. Two anchors (two pinned
// corners, the common case) are solved exactly in one round, including the touching balls of a
// taut row where plain alternating projections only creep towards the single feasible point.
//
// One tether, or two with both anchors kinematic (every particle of a cloth hung from two pins or
// held by two grippers), take the shortcuts of tether_projection.h: the same positions to the bit,
// without the square roots the rounds take twice.
double Solver::projectTethers(Particles& p, const ClothTopology& topology) {
  const std::vector<Tether>& tethers = topology.tethers;
  const std::size_t count = tethers.size();
  double max_change = 0.0, max_change_squared = 0.0;
  AnchorAxis axis;  // anchors stay put during the pass
  std::size_t end = 0;
  for (std::size_t begin = 0; begin < count; begin = end) {
    const int particle = tethers[begin].particle;
    end = begin + 1;
    while (end < count && tethers[end].particle == particle) ++end;
    if (p.inverse_mass[particle] == 0.0) continue;
    Vec3& x = p.position[particle];
    int first_round = 0;
    const Tether& t0 = tethers[begin];
    if (end - begin <= 2 && p.inverse_mass[t0.anchor] == 0.0) {
      double moved_squared = 0.0;
      if (end - begin == 1) {
        moved_squared = projectTetherSingle(x, p.mass[particle], p.position[t0.anchor],
                                            t0.max_length, reaction_[t0.anchor]);
        max_change_squared = std::max(max_change_squared, moved_squared);
        continue;
      }
      const Tether& t1 = tethers[begin + 1];
      if (p.inverse_mass[t1.anchor] == 0.0) {
        const bool settled = projectTetherPair(
            x, p.mass[particle], p.position[t0.anchor], t0.max_length, p.position[t1.anchor],
            t1.max_length, reaction_[t0.anchor], reaction_[t1.anchor], axis, moved_squared);
        max_change_squared = std::max(max_change_squared, moved_squared);
        if (settled) continue;
        first_round = 1;  // the rounds go on from the second, as they would have
      }
    }
    max_change = std::max(
        max_change, projectTetherRounds(x, p.mass[particle], &tethers[begin], tethers.data() + end,
                                        p.position, p.inverse_mass, reaction_, first_round));
  }
  return std::max(max_change, std::sqrt(max_change_squared));
}

// Jacobi: every correction of a pass was computed from the same positions and is applied here at
// once. The averaging (jacobiScale) is already in each constraint's step; without averaging the
// corrections are simply summed (REFERENCE_CASES.md case 7: x <- (1 - K) d).
void Solver::applyJacobi(Particles& p, double& max_change) {
  for (int i = 0; i < p.size(); ++i) {
    if (jacobi_count_[i] == 0) continue;
    p.position[i] += jacobi_delta_[i];
    max_change = std::max(max_change, jacobi_delta_[i].norm());
    jacobi_delta_[i].setZero();
  }
}

// n_k of the Jacobi averaging: the stretch and bending constraints acting on each free particle.
// The kinematic set is fixed during a step, so this runs once per step.
void Solver::countJacobiConstraints(const Particles& p, const ClothTopology& topology) {
  std::fill(jacobi_count_.begin(), jacobi_count_.end(), 0);
  for (const DistanceConstraint& con : topology.stretch) {
    if (!p.isKinematic(con.i)) ++jacobi_count_[con.i];
    if (!p.isKinematic(con.j)) ++jacobi_count_[con.j];
  }
  if (bend_compliance_ < 0.0 || config_.method == Method::kMassSpring) return;
  for (const BendConstraint& con : topology.bend) {
    for (int v = 0; v < 4; ++v) {
      if (!p.isKinematic(con.index[v])) ++jacobi_count_[con.index[v]];
    }
  }
}

double Solver::projectPass(double h, Particles& p, const ClothTopology& topology,
                           Collisions& collisions, bool first_pass, bool last_pass) {
  // The count of the last pass is what the step reports: constraints still degenerate at its end.
  startDegenerateCount();
  // Long-range levels first (solver.levels): they remove in one projection a stretch spread over
  // many links, which the cloth's own sweep carries one link per pass. Off while the cloth is
  // compliant (they are inextensible); the explicit springs do not come here.
  double max_change = 0.0;
  if (coarse_.levelCount() > 0 && stretch_compliance_ == 0.0) {
    max_change = in_columns_ ? coarse_.project(link_positions_.columns(), config_.simd,
                                               tracksLargestChange(), config_.avx512)
                             : coarse_.project(p, config_.levels_interpolate, config_.simd,
                                               tracksLargestChange(), config_.avx512);
  }
  max_change = std::max(max_change, projectStretch(h, p, topology, first_pass));
  max_change = std::max(max_change, projectBend(h, p, topology, first_pass, last_pass));
  if (config_.ordering == Ordering::kJacobi) applyJacobi(p, max_change);
  max_change = std::max(max_change, projectTethers(p, topology));
  // Contacts last in each pass so the positions a pass ends with are free of penetration.
  // Timed on their own: the narrow phase is the part of a pass a scene's collisions add.
  ScopedTimer timer(stats_.contact_time);
  max_change = std::max(max_change, collisions.project(p, topology));
  return max_change;
}

// Whether pass `pass` keeps the positions it starts from: every pass before the last one does, so
// that pass k >= 1 finds q^{k-1} in chebyshev_previous_.
bool Solver::chebyshevKeeps(int pass) const {
  return config_.chebyshev > 0.0 && pass + 1 < config_.iterations;
}

// solver.chebyshev: the Chebyshev semi-iterative method over a substep's passes (Wang 2015, "A
// Chebyshev Semi-Iterative Approach for Accelerating Projective and Position-based Dynamics").
// Pass k's result q^ is replaced by q^{k+1} = omega_{k+1} (q^ - q^{k-1}) + q^{k-1},
// with omega_1 = 2 / (2 - rho^2) at the first extrapolated pass and omega_{k+1} = 4 / (4 - rho^2
// omega_k) after it: the weights of the Chebyshev polynomials that damp every error mode whose
// factor per pass is at most rho. Pass 0 has no q^{k-1}, and the last pass is not extrapolated so
// that the substep ends with the contacts that pass projected (free of penetration) and the
// velocity update sees a projected state, not an extrapolated one. The multipliers are not
// extrapolated: a gripper's reported force (addMultiplierReactions) counts the passes' own
// corrections only.
// Returns omega_{k+1}, given the last pass's omega_k (unused at the first extrapolated pass).
double Solver::accelerate(int pass, double omega, Particles& p) {
  const double rho2 = config_.chebyshev * config_.chebyshev;
  omega = pass == 1 ? 2.0 / (2.0 - rho2) : 4.0 / (4.0 - rho2 * omega);
  pool_.runRanges(p.size(), [&](int begin, int end, int) {
    for (int i = begin; i < end; ++i) {
      if (p.inverse_mass[i] == 0.0) continue;  // kinematic: its path is prescribed
      p.position[i] = chebyshev_previous_[i] + omega * (p.position[i] - chebyshev_previous_[i]);
    }
  });
  return omega;
}

// Velocity update of PBD, v = (x - x_prev) / h; for Verlet this is the implicit velocity
// x_n - x_{n-1} the next step adds. Written as v = v~ + (x - x~) / h, x~ = x_prev + h v~ the
// prediction: the same value, but a particle no constraint moved keeps its velocity exactly
// instead of re-deriving it from two large positions (1e4 m from the origin, x - x_prev loses 1e-9
// of v per substep to rounding, 1.5e-5 m over a 1 s fall at 6 kHz; REFERENCE_CASES.md,
// "Precision"). Kinematic particles take the velocity of their prescribed motion.
void Solver::updateVelocities(double h, Particles& p) { advance(h, 1.0, true, false, p); }

// The explicit baseline: spring and damper forces, then symplectic Euler. Stable only while
// w_max h < 2 (REFERENCE_CASES.md case 8). Contacts are still projected, so the chart compares the
// cloth model, not the collision handling.
void Solver::massSpringSubstep(double h, double s_end, Particles& p, const ClothTopology& topology,
                               Collisions& collisions) {
  {
    ScopedTimer timer(stats_.project_time);
    massSpringForcesAndContacts(h, s_end, p, topology, collisions);
  }
  ScopedTimer timer(stats_.update_time);
  updateVelocities(h, p);
}

void Solver::massSpringForcesAndContacts(double h, double s_end, Particles& p,
                                         const ClothTopology& topology, Collisions& collisions) {
  const double k = config_.spring_stiffness, damper = config_.spring_damping;
  for (int i = 0; i < p.size(); ++i) force_[i] = p.mass[i] * config_.gravity;
  startDegenerateCount();
  const int count = static_cast<int>(topology.stretch.size());
  for (int c = 0; c < count; ++c) {
    const DistanceConstraint& con = topology.stretch[c];
    const Vec3 delta = p.position[con.i] - p.position[con.j];
    const double length = delta.norm();
    if (length < kMinLength) {  // coincident: no direction, reported as in projectStretch
      noteDegenerate(c);
      continue;
    }
    const Vec3 n = delta / length;
    const double relative_speed = (p.velocity[con.i] - p.velocity[con.j]).dot(n);
    const Vec3 f = (-k * (length - con.rest_length) - damper * relative_speed) * n;
    force_[con.i] += f;
    force_[con.j] -= f;
  }
  if (bend_compliance_ >= 0.0) {
    // Bending springs on the isometric energy E = k_b / 2 scale^2 |b|^2: F_k = -k_b scale^2 K_k b.
    const bool has_rest = !topology.bend_rest.empty();
    for (std::size_t c = 0; c < topology.bend.size(); ++c) {
      const BendConstraint& con = topology.bend[c];
      const Vec3 b = has_rest && topology.bend_rest[c].curved
                         ? Vec3(bendVector(con, p) - restBendVector(con, topology.bend_rest[c], p))
                         : bendVector(con, p);
      if (b.norm() < kMinLength) continue;  // flat: no force but rounding noise
      const Vec3 f = -config_.bend_spring_stiffness * con.scale * con.scale * b;
      for (int v = 0; v < 4; ++v) force_[con.index[v]] += con.weight[v] * f;
    }
  }
  // A kinematic particle's springs act on it like on any other; only it does not move. Their
  // force, times h^2, is its reaction (kg m) in the units of the projected constraints.
  for (int i = 0; i < p.size(); ++i) {
    if (p.inverse_mass[i] != 0.0) continue;
    reaction_[i] += (h * h) * (force_[i] - p.mass[i] * config_.gravity);
  }
  const double keep = dampingFactor(h);
  for (int i = 0; i < p.size(); ++i) {
    p.substep_start[i] = p.position[i];
    if (p.inverse_mass[i] == 0.0) {
      p.position[i] = (1.0 - s_end) * p.kinematic_from[i] + s_end * p.kinematic_to[i];
      continue;
    }
    p.velocity[i] = keep * p.velocity[i] + h * p.inverse_mass[i] * force_[i];
    p.position[i] += h * p.velocity[i];  // x~ = start + h v, as updateVelocities reads it
  }
  for (int pass = 0; pass < config_.iterations; ++pass) {
    ++stats_.iterations;
    if (collisions.project(p, topology) <= config_.tolerance) break;
  }
}

// The kinematic set is fixed during a step: the stretch constraints and hinges that join a
// kinematic to a free particle are listed once, so the reactions cost nothing for the others.
void Solver::startReactions(const Particles& p, const ClothTopology& topology, bool list) {
  std::fill(reaction_.begin(), reaction_.end(), Vec3::Zero());
  for (int i = 0; i < p.size(); ++i) {
    if (p.inverse_mass[i] == 0.0) start_velocity_[i] = p.velocity[i];
  }
  if (!list) return;  // the kinematic set of the last step
  kinematic_particles_.clear();
  for (int i = 0; i < p.size(); ++i) {
    if (p.inverse_mass[i] == 0.0) kinematic_particles_.push_back(i);
  }
  kinematic_stretch_.clear();
  kinematic_bend_.clear();
  if (config_.method == Method::kMassSpring) return;  // its springs report through force_
  const int stretch_count = static_cast<int>(topology.stretch.size());
  for (int c = 0; c < stretch_count; ++c) {
    const DistanceConstraint& con = topology.stretch[c];
    if ((p.inverse_mass[con.i] == 0.0) != (p.inverse_mass[con.j] == 0.0)) {
      kinematic_stretch_.push_back(c);
    }
  }
  if (bend_compliance_ < 0.0) return;
  const int bend_count = static_cast<int>(topology.bend.size());
  for (int c = 0; c < bend_count; ++c) {
    if (joinsKinematicToFree(topology.bend[c], p.inverse_mass.data())) kinematic_bend_.push_back(c);
  }
}

// After a substep's passes: each listed constraint's multiplier, summed over the passes, times
// its gradient at the kinematic particle (stretch: +-n; hinge: scale K_k) is the reaction there.
// Read after the passes instead of inside the projection loops, which stay as they are.
void Solver::addMultiplierReactions(const Particles& p, const ClothTopology& topology) {
  const PositionColumns columns = link_positions_.columns();
  auto position = [&](int i) {
    return in_columns_ ? Vec3(columns.x[i], columns.y[i], columns.z[i]) : p.position[i];
  };
  for (int c : kinematic_stretch_) {
    const DistanceConstraint& con = topology.stretch[c];
    const Vec3 delta = position(con.i) - position(con.j);
    const double length = delta.norm();
    if (length < kMinLength) continue;
    const Vec3 reaction = (stretchLambda(c, topology) / length) * delta;  // lambda grad_i C
    if (p.inverse_mass[con.i] == 0.0) {
      reaction_[con.i] += reaction;
    } else {
      reaction_[con.j] -= reaction;
    }
  }
  for (int c : kinematic_bend_) {
    const BendConstraint& con = topology.bend[c];
    for (int v = 0; v < 4; ++v) {
      const int i = con.index[v];
      if (p.inverse_mass[i] == 0.0) reaction_[i] += (con.scale * con.weight[v]) * bend_lambda_[c];
    }
  }
}

// Impulse over the step = sum of reactions / h (each is a force times h^2, applied once per
// substep); the force is that impulse / dt. The kinematic particle itself adds its weight and
// loses the momentum its prescribed motion gained.
void Solver::finishReactions(double dt, double h, const Particles& p,
                             const Collisions& collisions) {
  const double scale = 1.0 / (h * dt);
  const Vec3Array& contacts = collisions.kinematicReaction();
  for (int i = 0; i < p.size(); ++i) {
    if (p.inverse_mass[i] != 0.0) {
      constraint_force_[i].setZero();
      support_force_[i].setZero();
      continue;
    }
    constraint_force_[i] = scale * (reaction_[i] + contacts[i]);
    support_force_[i] = constraint_force_[i] +
                        p.mass[i] * (config_.gravity - (p.velocity[i] - start_velocity_[i]) / dt);
  }
}

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
  startDegenerateCount();
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

// The constraint passes of a substep (position-based methods: xpbd, pbd, verlet).
void Solver::projectSubstep(double h, Particles& p, const ClothTopology& topology,
                            Collisions& collisions) {
  ScopedTimer timer(stats_.project_time);
  // XPBD multipliers start at zero every substep (Small Steps, Algorithm 1). The flat links'
  // first pass writes theirs (projectStretch, lambda_from_zero); the others are cleared here.
  if (config_.ordering == Ordering::kJacobi || !fastStretch(topology)) {
    std::fill(stretch_lambda_.begin(), stretch_lambda_.end(), 0.0);
  }
  // The flat hinges' first pass writes theirs (projectFlatHinges, lambda_from_zero).
  if (!flatBend(topology)) std::fill(bend_lambda_.begin(), bend_lambda_.end(), Vec3::Zero());
  double omega = 1.0;  // solver.chebyshev: the last extrapolation's weight in this substep
  for (int pass = 0; pass < config_.iterations; ++pass) {
    ++stats_.iterations;
    if (chebyshevKeeps(pass)) {
      std::swap(chebyshev_previous_, chebyshev_current_);  // no copy: the buffers trade places
      chebyshev_current_ = p.position;                     // same size: no allocation
    }
    const double max_change =
        projectPass(h, p, topology, collisions, pass == 0, pass + 1 == config_.iterations);
    if (pass >= 1 && chebyshevKeeps(pass)) omega = accelerate(pass, omega, p);
    // Adaptive count (seed: "measuring the change from last iteration").
    if (tracksLargestChange() && max_change < config_.tolerance) break;
  }
  addMultiplierReactions(p, topology);
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
  stats_.degenerate_constraints = degenerate_in_pass_;
  stats_.first_degenerate_constraint = first_degenerate_in_pass_;
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
