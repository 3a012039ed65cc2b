// The substep controller of solver.target_max_strain (accuracy_controller.h).
#include "pbd_cloth/sim/accuracy_controller.h"

#include <algorithm>
#include <cmath>

namespace pbd_cloth {

void AccuracyController::configure(const SolverConfig& solver) {
  const bool was_active = active_;
  target_strain_ = solver.target_max_strain;
  target_penetration_ = solver.target_penetration;
  min_substeps_ = solver.min_substeps;
  max_substeps_ = std::max(solver.min_substeps, solver.max_substeps);
  active_ = target_strain_ > 0.0 || target_penetration_ > 0.0;
  if (active_ && !was_active) {
    substeps_ = solver.substeps;
    calm_steps_ = 0;
  }
  substeps_ = std::clamp(substeps_, min_substeps_, max_substeps_);
}

void AccuracyController::restore(int substeps, int calm_steps) {
  substeps_ = std::clamp(substeps, min_substeps_, max_substeps_);
  calm_steps_ = calm_steps;
}

double AccuracyController::ratio(double strain, double penetration) const {
  double r = 0.0;
  if (target_strain_ > 0.0) r = std::max(r, strain / target_strain_);
  if (target_penetration_ > 0.0) r = std::max(r, penetration / target_penetration_);
  // A non-finite error (a step that blew up) is as far over the target as can be.
  return std::isfinite(r) ? r : 1e30;
}

// n sqrt(r / kAim), at least one more than n, at most 4 n and max_substeps.
int AccuracyController::raised(double ratio) const {
  const double wanted = std::ceil(substeps_ * std::sqrt(std::min(ratio, 1e6) / kAim));
  const int limit = std::min(max_substeps_, 4 * substeps_);
  return std::min(limit, std::max(substeps_ + 1, static_cast<int>(wanted)));
}

// From the second redo on: the rate the error fell at between the last two attempts,
// r ~ n^-p, gives n (r / kAim)^(1/p) (accuracy_controller.h).
int AccuracyController::raisedAtRate(double ratio) const {
  const int limit = std::min(max_substeps_, 4 * substeps_);
  if (!(previous_ratio_ > ratio) || previous_substeps_ >= substeps_) return limit;
  const double rate = std::clamp(std::log(previous_ratio_ / ratio) /
                                     std::log(static_cast<double>(substeps_) / previous_substeps_),
                                 0.25, 2.0);
  const double wanted = std::ceil(substeps_ * std::pow(std::min(ratio, 1e6) / kAim, 1.0 / rate));
  return static_cast<int>(std::min<double>(limit, std::max<double>(substeps_ + 1, wanted)));
}

bool AccuracyController::redo(double ratio, int attempt) {
  if (!active_ || ratio <= kRedo || attempt >= kMaxRedos || substeps_ >= max_substeps_) {
    return false;
  }
  const int next = attempt == 0 ? raised(ratio) : raisedAtRate(ratio);
  previous_substeps_ = substeps_;
  previous_ratio_ = ratio;
  substeps_ = next;
  calm_steps_ = 0;
  return true;
}

void AccuracyController::update(double ratio) {
  if (!active_) return;
  calm_steps_ = ratio < kMargin ? calm_steps_ + 1 : 0;
  if (ratio > 1.0) {
    substeps_ = raised(ratio);
  } else if (calm_steps_ >= kCalmSteps) {
    const double wanted = std::floor(substeps_ * std::sqrt(ratio / kAim));
    const int most_fewer = std::max(1, substeps_ / 8);
    substeps_ = std::max({min_substeps_, substeps_ - most_fewer, static_cast<int>(wanted)});
  }
}

}  // namespace pbd_cloth
