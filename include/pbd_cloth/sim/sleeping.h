// Sleeping (solver.sleep_speed, solver.sleep_time): whether a scene at rest may skip its solve.
//
// A scene whose free particles all stayed slower than solver.sleep_speed for solver.sleep_time is
// at rest: its next solve would move nothing but rounding. Slower on average: each stayed within
// sleep_speed x sleep_time of where it was when the stillness began, so a resting garment whose
// contacts nudge a particle by micrometres in one substep and back (a velocity of a centimetre a
// second for that substep) still counts as still. It then sleeps: a step checks what could move
// it, and while nothing does, only time advances (the particles keep their positions, at zero
// velocity). It wakes, and that step solves, when a pinned or held particle is to move, a collider
// moving near the particles' bounds (or enabled, disabled, set), or wake() from outside (grasp and
// release, set_state, reset, solver, cloth or friction parameters). One region, the whole scene: a
// cloth is one connected body, and a part of it at rest next to a moving part is pulled along at
// once.
#pragma once

#include "pbd_cloth/collision/collisions.h"
#include "pbd_cloth/config/scene_config.h"
#include "pbd_cloth/model/particles.h"

namespace pbd_cloth {

class Sleeping {
 public:
  // After a build: the stillness starts again, with room for every particle's position (so that
  // update() copies without allocating). Whether the scene sleeps is left as it is (wake()).
  void build(const Particles& particles);

  bool asleep() const { return asleep_; }
  // Steps slept through since construction (each cost a check, not a solve).
  long sleptSteps() const { return slept_steps_; }
  void wake();

  // Asleep, whether the next step may be slept through: no pinned or held particle is to move
  // (kinematic targets set for the step), no collider was set, enabled or disabled, none moves
  // near the particles.
  bool canSleepThrough(const Particles& particles, const Collisions& collisions) const;
  void countSleptStep() { ++slept_steps_; }
  // After a solved step of dt: the stillness goes on or begins again; long enough, the scene falls
  // asleep, its free particles at rest.
  void update(const SolverConfig& solver, Particles& particles, const Collisions& collisions,
              double dt);

 private:
  // How long every free particle has stayed within sleep_speed x sleep_time of where it was when
  // the stillness began (still_from_), whether the scene sleeps, the particles' bounds when it
  // fell asleep, and the collider change count then.
  double still_time_ = 0.0;
  bool still_begun_ = false;
  Vec3Array still_from_;
  bool asleep_ = false;
  long slept_steps_ = 0;
  Vec3 sleep_lo_ = Vec3::Zero();
  Vec3 sleep_hi_ = Vec3::Zero();
  double sleep_margin_ = 0.0;  // m around those bounds where a moving collider wakes the scene
  long sleep_collider_changes_ = 0;
};

}  // namespace pbd_cloth
