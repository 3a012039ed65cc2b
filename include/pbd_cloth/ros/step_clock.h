// When the node steps, so that simulated time follows ROS time: ros::Time::now(), which is /clock
// when /use_sim_time is true and the wall clock otherwise.
//
// The state at simulated time t (Simulation::time()) is the world at ROS time origin + t; that sum
// is the stamp of everything published from it. A step is due once ROS time has reached its end,
// so a state is never ahead of ROS time. The origin is the first non-zero ROS time seen (time 0
// means "no /clock yet"), and it moves in two cases only:
// - more than max_catch_up_steps are due (a slow machine, /clock jumping ahead): the node runs that
//   many and moves the origin forward over the rest, so simulated time slows down instead of
//   piling up work it cannot do;
// - ROS time goes back (a looping rosbag): the origin becomes the new time and the caller resets
//   the simulation, since the world it was following has started over.
#pragma once

#include <ros/time.h>

namespace pbd_cloth {

class StepClock {
 public:
  struct Config {
    double step_period = 1.0 / 120.0;  // s, 1 / step_rate
    int max_catch_up_steps = 10;       // ~max_catch_up_steps, >= 1
  };

  // What update() found.
  struct Plan {
    bool waiting = false;      // ROS time is 0: /use_sim_time is true and no /clock arrived yet
    bool started = false;      // the first ROS time seen: it is the origin, nothing is due yet
    bool jumped_back = false;  // ROS time went back: origin = now, the caller resets the simulation
    double jump = 0.0;         // s ROS time went back by
    int steps = 0;             // steps due now, at most max_catch_up_steps
    double behind = 0.0;       // s the state was behind ROS time
    double skipped = 0.0;      // s the origin moved forward (> 0 only when more steps were due)
  };

  StepClock() = default;
  explicit StepClock(const Config& config) : config_(config) {}

  // Called with the current ROS time and Simulation::time(); the caller then runs plan.steps
  // steps (or fewer, carrying the rest over to the next call).
  Plan update(const ros::Time& now, double sim_time);

  // Simulated time 0 is at `origin` from now on (the simulation was reset). A zero origin means
  // "not started": the next non-zero time seen becomes the origin.
  void restart(const ros::Time& origin);

  // A saved state was set (~set_state): the state at simulated time `sim_time` is the world at ROS
  // time `stamp` from now on, so stamps keep going forward while simulated time jumps. When the
  // state is later than `stamp` (sim_time > stamp, e.g. /clock restarted at 0) the origin is 0 and
  // the state is stamped sim_time: no step is due until ROS time reaches it. A zero stamp means
  // "not started": the first non-zero ROS time seen becomes the stamp of the current state.
  void continueFrom(const ros::Time& stamp, double sim_time);

  // The ROS time of the state at simulated time `sim_time`.
  ros::Time stateTime(double sim_time) const { return origin_ + ros::Duration(sim_time); }
  const ros::Time& origin() const { return origin_; }
  bool started() const { return started_; }
  const Config& config() const { return config_; }

 private:
  Config config_;
  bool started_ = false;
  ros::Time origin_;
  ros::Time last_now_;  // the latest ROS time seen, to notice it going back
};

}  // namespace pbd_cloth
