// Turns pose samples that arrive at their own rate (a ~<name>/pose topic, a tf frame) into one
// target pose per simulation step, so a gripper or obstacle commanded at 10 Hz does not jump once
// every 12 steps of a 120 Hz simulation.
//
// Policy: first-order hold with one sample period of latency. When a sample arrives, the body
// moves from where it is to the new pose at constant speed, arriving when the next sample is
// expected (after the estimated sample period). The motion never goes beyond the latest pose:
// extrapolating a gripper that holds cloth overshoots whenever the commanded motion stops or turns,
// and a late correction would then yank the cloth back. Samples faster than the steps simply make
// each step go to the latest pose. The core interpolates each step's motion across its substeps.
//
// Times are ROS time (the node passes ros::Time::now(), /clock under /use_sim_time) as plain
// seconds, and the node asks for the pose at the simulated time of each step's end: a gripper then
// moves as fast in simulated time as it does in the world, whatever the real-time factor.
// ROS-free, so the policy is testable without a master.
#pragma once

#include "pbd_cloth/config/scene_config.h"

namespace pbd_cloth {

class PoseFollower {
 public:
  struct Config {
    // s: the period assumed until two samples have arrived.
    double default_period = 0.1;
    // s: gaps longer than this (a user typing poses by hand) count as this long, so a lone sample
    // after a pause moves the body within max_period instead of creeping towards it.
    double max_period = 0.5;
    // Weight of the newest interval in the running period estimate, in (0, 1].
    double period_smoothing = 0.3;
  };

  PoseFollower() = default;
  explicit PoseFollower(const Config& config) : config_(config) {}

  // A new commanded pose arrived at ROS time `now` (s); `current` is where the body is now.
  void addSample(const Pose& current, const Pose& target, double now);
  // True once a sample has arrived (since construction or reset): the body is driven by samples.
  bool active() const { return active_; }
  // The pose to reach at ROS time `time` (s): on the way from the pose at the last sample to the
  // sample, or the sample itself once the expected period has passed.
  Pose poseAt(double time) const;
  // The estimated sample period (s).
  double period() const { return period_; }
  // Forget everything, e.g. when the simulation is reset and the body jumps back.
  void reset();

 private:
  Config config_;
  bool active_ = false;
  bool have_period_ = false;
  double last_arrival_ = 0.0;  // ROS time of the last sample (s)
  double period_ = Config().default_period;
  Pose start_;   // where the body was when the last sample arrived
  Pose target_;  // the last sample
};

}  // namespace pbd_cloth
