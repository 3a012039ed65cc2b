#include "pbd_cloth/ros/pose_follower.h"

#include <algorithm>

#include "pbd_cloth/sim/simulation.h"

namespace pbd_cloth {

void PoseFollower::addSample(const Pose& current, const Pose& target, double now) {
  if (!active_) {
    period_ = config_.default_period;
  } else {
    const double interval = std::min(std::max(now - last_arrival_, 0.0), config_.max_period);
    // The first measured interval replaces the guess outright; later ones are averaged so one
    // late message does not halve the speed of the next motion.
    period_ = have_period_
                  ? (1.0 - config_.period_smoothing) * period_ + config_.period_smoothing * interval
                  : interval;
    have_period_ = true;
  }
  active_ = true;
  last_arrival_ = now;
  start_ = current;
  target_ = target;
}

Pose PoseFollower::poseAt(double time) const {
  if (period_ <= 0.0) {
    return target_;
  }
  const double s = std::min(std::max((time - last_arrival_) / period_, 0.0), 1.0);
  return interpolate(start_, target_, s);
}

void PoseFollower::reset() { *this = PoseFollower(config_); }

}  // namespace pbd_cloth
