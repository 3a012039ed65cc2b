#include "pbd_cloth/ros/step_clock.h"

#include <algorithm>
#include <cmath>

namespace pbd_cloth {
namespace {

// Simulated time is a sum of step periods and ROS time has nanosecond resolution: a step whose end
// lands within this fraction of a period of `now` is due, not left for the next call.
constexpr double kDueTolerance = 1e-6;

}  // namespace

StepClock::Plan StepClock::update(const ros::Time& now, double sim_time) {
  Plan plan;
  if (now.isZero()) {
    plan.waiting = true;
    return plan;
  }
  if (!started_) {
    continueFrom(now, sim_time);
    plan.started = true;
    return plan;
  }
  if (now < last_now_) {
    plan.jumped_back = true;
    plan.jump = (last_now_ - now).toSec();
    restart(now);
    return plan;
  }
  last_now_ = now;

  const double period = config_.step_period;
  plan.behind = std::max((now - stateTime(sim_time)).toSec(), 0.0);
  const double due = std::floor(plan.behind / period + kDueTolerance);
  if (due > config_.max_catch_up_steps) {
    // Whole periods only, so the steps stay on the same grid of ROS time.
    const double skipped_steps = due - config_.max_catch_up_steps;
    plan.skipped = skipped_steps * period;
    origin_ += ros::Duration(plan.skipped);
    plan.steps = config_.max_catch_up_steps;
  } else {
    plan.steps = static_cast<int>(due);
  }
  return plan;
}

void StepClock::continueFrom(const ros::Time& stamp, double sim_time) {
  origin_ = stamp.toSec() > sim_time ? stamp - ros::Duration(sim_time) : ros::Time();
  last_now_ = stamp;
  started_ = !stamp.isZero();
}

void StepClock::restart(const ros::Time& origin) {
  origin_ = origin;
  last_now_ = origin;
  started_ = !origin.isZero();
}

}  // namespace pbd_cloth
