// Wall time of a phase of the step, added into one StepStats field when the scope ends (RAII), so
// the step reads as its phases and not as the clock reads around them.
#pragma once

#include <chrono>

namespace pbd_cloth {

class ScopedTimer {
 public:
  explicit ScopedTimer(double& seconds) : seconds_(seconds), begin_(Clock::now()) {}
  ~ScopedTimer() { seconds_ += std::chrono::duration<double>(Clock::now() - begin_).count(); }
  ScopedTimer(const ScopedTimer&) = delete;
  ScopedTimer& operator=(const ScopedTimer&) = delete;

 private:
  using Clock = std::chrono::steady_clock;
  double& seconds_;
  Clock::time_point begin_;
};

}  // namespace pbd_cloth
