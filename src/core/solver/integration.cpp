// Prediction and velocity update of the position-based methods (the kernels they run:
// prediction_kernels.h).
#include "pbd_cloth/solver/solver.h"

#include "pbd_cloth/parallel/cpu_features.h"
#include "pbd_cloth/solver/prediction_kernels.h"

namespace pbd_cloth {

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
  const bool avx2 = config_.simd && cpuHasAvx2();
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

// Velocity update of PBD, v = (x - x_prev) / h; for Verlet this is the implicit velocity
// x_n - x_{n-1} the next step adds. Written as v = v~ + (x - x~) / h, x~ = x_prev + h v~ the
// prediction: the same value, but a particle no constraint moved keeps its velocity exactly
// instead of re-deriving it from two large positions (1e4 m from the origin, x - x_prev loses 1e-9
// of v per substep to rounding, 1.5e-5 m over a 1 s fall at 6 kHz; REFERENCE_CASES.md,
// "Precision"). Kinematic particles take the velocity of their prescribed motion.
void Solver::updateVelocities(double h, Particles& p) { advance(h, 1.0, true, false, p); }

}  // namespace pbd_cloth
