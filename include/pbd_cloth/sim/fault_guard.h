// Fault recovery: the check after each step (non-finite or too fast particles) and the roll-back
// of a step that cannot stand to the positions it started from. Also the test hook that corrupts
// a step from inside, so a test can see the recovery catch it.
#pragma once

#include <cstdint>
#include <string>

#include "pbd_cloth/model/particles.h"

namespace pbd_cloth {

// A step whose result could not stand (Simulation::step, fault recovery).
struct StepFault {
  enum class Kind {
    kNone,
    kNonFinite,  // a particle's position or velocity is NaN or Inf
    kTooFast,    // a free particle moves faster than solver.max_speed: an energy blow-up
  };
  Kind kind = Kind::kNone;
  int particle = -1;   // the first particle found at fault
  double speed = 0.0;  // its speed (m/s), kTooFast
  double time = 0.0;   // simulated time at the end of the step that was undone (s)
};

// "particle 12 not finite" / "particle 12 at 1.3e+04 m/s (solver.max_speed 100 m/s)".
std::string describe(const StepFault& fault, double max_speed);

// The check itself: the first non-finite particle, else the first free one faster than max_speed
// (kNone: the state can stand). `time` goes into the fault.
StepFault findFault(const Particles& particles, double max_speed, double time);

// Faults a test can inject inside the next step (Simulation::injectFaultForTesting).
enum class InjectedFault {
  kNaN,     // the first free particle's position becomes NaN before the constraints are solved
  kBlowUp,  // after they are, the first free particle gets 1000 x solver.max_speed more speed
};

class FaultGuard {
 public:
  void setEnabled(bool on) { enabled_ = on; }
  bool enabled() const { return enabled_; }
  // After a build: room for every particle's position, so the copy each step allocates nothing.
  void build(const Particles& particles);

  // Before the step: the positions to go back to (when enabled).
  void rememberStart(const Particles& particles);
  // After the step: when enabled and the step cannot stand, it is undone (true): free particles
  // back to the start of the step, at rest; kinematic ones keep the positions their grippers gave
  // them (finite: every pose is checked on the way in).
  bool checkStep(Particles& particles, double max_speed, double time);

  // Steps undone since construction (a build does not clear it), whether the last one was, and
  // the fault of the latest undone step.
  std::uint64_t restoredSteps() const { return restored_steps_; }
  bool lastStepRestored() const { return last_step_restored_; }
  void clearLastStepRestored() { last_step_restored_ = false; }
  const StepFault& lastFault() const { return last_fault_; }

  // Test hook: the next step is corrupted (InjectedFault says where).
  void inject(InjectedFault fault) { injected_fault_ = fault, inject_ = true; }
  bool injecting() const { return inject_; }
  // Called before the solve (kNaN) and after it (kBlowUp): injects when that is the place.
  void injectBeforeSolve(Particles& particles, double max_speed, double dt) {
    if (inject_ && injected_fault_ == InjectedFault::kNaN) injectFault(particles, max_speed, dt);
  }
  void injectAfterSolve(Particles& particles, double max_speed, double dt) {
    if (inject_ && injected_fault_ == InjectedFault::kBlowUp) injectFault(particles, max_speed, dt);
  }

 private:
  void undoStep(Particles& particles, const StepFault& fault);
  void injectFault(Particles& particles, double max_speed, double dt);

  bool enabled_ = false;
  Vec3Array good_position_;  // the particles' positions at the start of the step
  std::uint64_t restored_steps_ = 0;
  bool last_step_restored_ = false;
  StepFault last_fault_;
  bool inject_ = false;
  InjectedFault injected_fault_ = InjectedFault::kNaN;
};

}  // namespace pbd_cloth
