#include "pbd_cloth/ros/real_time_factor.h"

namespace pbd_cloth {

void RealTimeFactor::add(double wall_time, double sim_time) {
  samples_.emplace_back(wall_time, sim_time);
  // Keep one sample at or beyond the window edge so the ratio spans a full window.
  while (samples_.size() > 2 && samples_[1].first <= wall_time - window_) {
    samples_.pop_front();
  }
}

double RealTimeFactor::value() const {
  const double wall = span();
  if (wall <= 0.0) {
    return 0.0;
  }
  return (samples_.back().second - samples_.front().second) / wall;
}

}  // namespace pbd_cloth
