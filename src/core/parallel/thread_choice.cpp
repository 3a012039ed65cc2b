#include "pbd_cloth/parallel/thread_choice.h"

#include <algorithm>
#include <cmath>

namespace pbd_cloth {

void ThreadChoice::reset(bool solo) {
  *this = ThreadChoice();
  preferred_solo_ = current_solo_ = solo;
}

double ThreadChoice::historyMean() const {
  double sum = 0.0;
  for (int k = 0; k < history_count_; ++k) sum += history_[k];
  return sum / history_count_;
}

bool ThreadChoice::next(double step_seconds) {
  const bool counted = std::isfinite(step_seconds) && step_seconds >= 0.0;
  if (probe_step_ >= 0) {
    // The step just run was one of the probe's, in the other mode.
    const bool too_slow = counted && step_seconds > kAbortFactor * historyMean();
    if (probe_step_ > 0 && counted) {
      probe_sum_ += step_seconds;
      ++probe_counted_;
    }
    if (++probe_step_ < kProbeSteps && !too_slow) return current_solo_;  // the probe goes on
    ++probes_;
    probe_step_ = -1;
    const bool faster = !too_slow && probe_counted_ > 0 &&
                        probe_sum_ / probe_counted_ < (1.0 - kSwitchMargin) * historyMean();
    if (faster) {
      // The other mode is now the preferred one; its history starts afresh.
      preferred_solo_ = !preferred_solo_;
      ++switches_;
      history_count_ = history_next_ = 0;
      interval_ = kFirstInterval;
    } else {
      interval_ = std::min(2 * interval_, kLongestInterval);
      skip_next_ = true;
    }
    until_probe_ = interval_;
    current_solo_ = preferred_solo_;
    return current_solo_;
  }
  // A step of the preferred mode.
  if (skip_next_) {
    skip_next_ = false;
  } else if (counted) {
    history_[history_next_] = step_seconds;
    history_next_ = (history_next_ + 1) % kHistory;
    history_count_ = std::min(history_count_ + 1, kHistory);
  }
  if (until_probe_ > 0) --until_probe_;
  if (until_probe_ == 0 && history_count_ == kHistory) {
    probe_step_ = 0;
    probe_sum_ = 0.0;
    probe_counted_ = 0;
    current_solo_ = !preferred_solo_;
    return current_solo_;
  }
  current_solo_ = preferred_solo_;
  return current_solo_;
}

}  // namespace pbd_cloth
