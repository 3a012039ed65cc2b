// Which states the node publishes: the first one at or after each multiple of 1/publish_rate of
// simulated time. Counting in simulated time keeps publish_rate a rate of the simulated world
// whatever the clock does: a node below real time publishes less often per wall second, a node
// that is the clock (~publish_clock) more often, and each message still stands for 1/publish_rate
// of simulated time.
#pragma once

#include <cmath>

namespace pbd_cloth {

class PublishTicks {
 public:
  explicit PublishTicks(double rate = 30.0) : rate_(rate) {}

  // True when the state at `sim_time` (s) is the first at or past the next tick; the tick then
  // counts as published.
  bool due(double sim_time) {
    // The tolerance: a step that lands on a tick (4 steps of 1/120 s = 1/30 s) may sum to a hair
    // below it.
    const long long tick = static_cast<long long>(std::floor(sim_time * rate_ + 1e-6));
    if (tick <= last_tick_) return false;
    last_tick_ = tick;
    return true;
  }

  // Simulated time is back at `sim_time` (0 after a reset, a saved state's time after ~set_state);
  // the state then is published by whoever set it.
  void restart(double sim_time = 0.0) {
    last_tick_ = static_cast<long long>(std::floor(sim_time * rate_ + 1e-6));
  }

 private:
  double rate_;
  long long last_tick_ = 0;
};

}  // namespace pbd_cloth
