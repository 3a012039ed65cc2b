// Simulated seconds per wall second over a sliding window. The step timer never queues missed
// ticks: when a step overruns its period the simulation simply falls behind wall time, and this
// ratio is how a user sees it (1.0 = real time).
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
