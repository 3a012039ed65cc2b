#include "pbd_cloth/sim/fault_guard.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>

namespace pbd_cloth {

std::string describe(const StepFault& fault, double max_speed) {
  std::ostringstream out;
  switch (fault.kind) {
    case StepFault::Kind::kNone:
      return "no fault";
    case StepFault::Kind::kNonFinite:
      out << "particle " << fault.particle << " not finite";
      break;
    case StepFault::Kind::kTooFast:
      out << "particle " << fault.particle << " at " << fault.speed << " m/s (solver.max_speed "
          << max_speed << " m/s)";
      break;
  }
  out << " at t = " << fault.time << " s";
  return out.str();
}

StepFault findFault(const Particles& particles, double max_speed, double time) {
  StepFault fault;
  fault.time = time;
  const double max_speed_sq = max_speed * max_speed;
  for (int i = 0; i < particles.size(); ++i) {
    const Vec3& x = particles.position[i];
    const Vec3& v = particles.velocity[i];
    // One finiteness test for both: a sum of finite numbers is finite unless it overflows, and
    // any NaN or Inf term makes it non-finite.
    if (!std::isfinite(x.sum() + v.sum())) {
      fault.kind = StepFault::Kind::kNonFinite;
      fault.particle = i;
      return fault;
    }
    if (fault.kind == StepFault::Kind::kNone && !particles.isKinematic(i) &&
        v.squaredNorm() > max_speed_sq) {
      // Keep looking: a non-finite particle further on is the worse news.
      fault.kind = StepFault::Kind::kTooFast;
      fault.particle = i;
      fault.speed = v.norm();
    }
  }
  return fault;
}

void FaultGuard::build(const Particles& particles) {
  good_position_ = particles.position;
  last_step_restored_ = false;
}

void FaultGuard::rememberStart(const Particles& particles) {
  if (enabled_) {
    std::copy(particles.position.begin(), particles.position.end(), good_position_.begin());
  }
}

bool FaultGuard::checkStep(Particles& particles, double max_speed, double time) {
  if (!enabled_) return false;
  const StepFault fault = findFault(particles, max_speed, time);
  if (fault.kind == StepFault::Kind::kNone) return false;
  undoStep(particles, fault);
  return true;
}

void FaultGuard::undoStep(Particles& particles, const StepFault& fault) {
  for (int i = 0; i < particles.size(); ++i) {
    const bool keep = particles.isKinematic(i) && std::isfinite(particles.position[i].sum());
    if (!keep) particles.position[i] = good_position_[i];
    particles.velocity[i].setZero();
    particles.substep_start[i] = particles.position[i];
    particles.step_start[i] = particles.position[i];
  }
  ++restored_steps_;
  last_step_restored_ = true;
  last_fault_ = fault;
}

// A NaN goes in before the solver, which spreads it through the constraints. A blow-up goes in
// after it, as if the solver had produced it: a single fast particle going in would be pulled back
// by its zero-compliance links within the step (PBD's unconditional stability), testing nothing.
void FaultGuard::injectFault(Particles& particles, double max_speed, double dt) {
  inject_ = false;
  for (int i = 0; i < particles.size(); ++i) {
    if (particles.isKinematic(i)) continue;
    if (injected_fault_ == InjectedFault::kNaN) {
      particles.position[i].x() = std::numeric_limits<double>::quiet_NaN();
    } else {
      const Vec3 kick(1000.0 * max_speed, 0.0, 0.0);
      particles.velocity[i] += kick;
      particles.position[i] += kick * dt;
    }
    return;
  }
}

}  // namespace pbd_cloth
