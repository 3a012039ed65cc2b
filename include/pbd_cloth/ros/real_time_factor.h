// Simulated seconds per wall second over a sliding window: how a user sees that the node cannot
// keep up (below 1; the catch-up of step_clock.h is bounded, so a slow node falls behind) or, as
// the clock (~publish_clock), how much faster than real time it runs. Always the wall clock, also
// under /use_sim_time: it measures the machine, not the clock.
#pragma once

#include <deque>
#include <utility>

namespace pbd_cloth {

class RealTimeFactor {
 public:
  explicit RealTimeFactor(double window = 1.0) : window_(window) {}

  // One sample per step: wall clock (s, any origin) and simulated time (s).
  void add(double wall_time, double sim_time);
  // Ratio over the last `window` wall seconds; 0 until two samples span some wall time.
  double value() const;
  // Wall seconds the samples cover: a factor over a short span after start or reset says little.
  double span() const {
    return samples_.size() < 2 ? 0.0 : samples_.back().first - samples_.front().first;
  }
  // Forget the history, e.g. when the simulated time jumps back on reset.
  void clear() { samples_.clear(); }

 private:
  double window_;
  std::deque<std::pair<double, double>> samples_;  // (wall, sim), oldest first
};

}  // namespace pbd_cloth
