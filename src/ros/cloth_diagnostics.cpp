#include "pbd_cloth/ros/cloth_diagnostics.h"

#include <algorithm>

#include <diagnostic_msgs/DiagnosticStatus.h>

namespace pbd_cloth {

using diagnostic_msgs::DiagnosticStatus;

ClothDiagnostics::ClothDiagnostics(const ros::NodeHandle& nh, const ros::NodeHandle& nh_private,
                                   const std::string& node_name, const Config& config)
    : config_(config), updater_(nh, nh_private, node_name) {
  // A simulator has no hardware; "none" is diagnostic_updater's convention for that.
  updater_.setHardwareID("none");
  updater_.add("simulation", this, &ClothDiagnostics::simulationStatus);
  updater_.add("inputs", this, &ClothDiagnostics::inputStatus);
}

void ClothDiagnostics::addStep(double step_wall_time, int truncated_searches, bool on_one_thread) {
  ++step_count_;
  if (on_one_thread) ++one_thread_steps_;
  step_time_sum_ += step_wall_time;
  step_time_max_ = std::max(step_time_max_, step_wall_time);
  truncated_searches_ += truncated_searches;
}

void ClothDiagnostics::report(const SimulationHealth& health, const InputRejections& rejections) {
  health_ = health;
  rejections_ = &rejections;
  updater_.force_update();
  rejections_ = nullptr;
  step_count_ = 0;
  step_time_sum_ = 0.0;
  step_time_max_ = 0.0;
  truncated_searches_ = 0;
  one_thread_steps_ = 0;
}

void ClothDiagnostics::simulationStatus(diagnostic_updater::DiagnosticStatusWrapper& status) {
  const double mean_step = step_count_ > 0 ? step_time_sum_ / step_count_ : 0.0;
  const bool slow_rate =
      health_.real_time_factor_valid && health_.real_time_factor < config_.min_real_time_factor;
  const bool slow_steps = mean_step > health_.step_period;
  const bool slow_clock =
      health_.clock_factor_valid && health_.clock_factor < config_.min_real_time_factor;
  const std::uint64_t restored = health_.restored_steps - restored_at_last_report_;
  restored_at_last_report_ = health_.restored_steps;
  if (!health_.finite) {
    status.summary(DiagnosticStatus::ERROR,
                   "the simulation diverged (non-finite positions): ~state is not published; "
                   "call ~reset");
  } else if (restored > 0) {
    status.summaryf(DiagnosticStatus::ERROR,
                    "%llu step(s) failed since the last report and were undone, back to the last "
                    "good state (latest: %s)",
                    static_cast<unsigned long long>(restored), health_.last_fault.c_str());
  } else if (health_.time_source == TimeSource::kWallClock && (slow_rate || slow_steps)) {
    status.summaryf(DiagnosticStatus::WARN,
                    "cannot keep real time: real-time factor %.2f, a step takes %.1f ms for a "
                    "period of %.1f ms (%s)",
                    health_.real_time_factor, 1e3 * mean_step, 1e3 * health_.step_period,
                    truncated_searches_ > 0
                        ? "the cloth is crushed into itself: self-collision searches hit their "
                          "candidate budget"
                        : "lower step_rate, substeps or the cloth size");
  } else if (health_.time_source == TimeSource::kRosClock && slow_clock) {
    // /clock may run at any speed: what matters is whether the steps keep up with it.
    status.summaryf(DiagnosticStatus::WARN,
                    "cannot keep up with /clock: %.2f simulated s per s of /clock (real-time "
                    "factor %.2f, a step takes %.1f ms; lower step_rate, substeps or the cloth "
                    "size, or slow /clock down)",
                    health_.clock_factor, health_.real_time_factor, 1e3 * mean_step);
  } else if (health_.target_budget_exhausted) {
    status.summaryf(DiagnosticStatus::WARN,
                    "accuracy target not met within the budget: target max strain %.3g %%, "
                    "reached %.3g %%; target penetration %.3g m, reached %.3g m; at "
                    "solver.max_substeps %d (raise it, lower step_rate, or relax the target)",
                    100.0 * health_.target_max_strain, 100.0 * health_.structural_max_strain,
                    health_.target_penetration, health_.max_penetration, health_.max_substeps);
  } else if (health_.degenerate_constraints > 0) {
    status.summaryf(DiagnosticStatus::WARN,
                    "%d stretch constraint(s) skipped in the last step: their particles coincide",
                    health_.degenerate_constraints);
  } else if (truncated_searches_ > 0) {
    status.summaryf(DiagnosticStatus::WARN,
                    "%d self-collision search(es) since the last report stopped at their "
                    "candidate budget: the cloth is crushed into itself, some of its self-contacts "
                    "skipped",
                    truncated_searches_);
  } else if (health_.time_source == TimeSource::kRosClock) {
    status.summary(DiagnosticStatus::OK, "keeping up with /clock");
  } else if (health_.time_source == TimeSource::kOwnClock) {
    status.summaryf(DiagnosticStatus::OK, "publishing /clock (real-time factor %.2f)",
                    health_.real_time_factor);
  } else {
    status.summary(DiagnosticStatus::OK, "keeping real time");
  }
  status.add("sim time (s)", health_.sim_time);
  status.add("real-time factor", health_.real_time_factor);
  if (health_.time_source == TimeSource::kRosClock) {
    status.add("simulated s per s of /clock", health_.clock_factor);
  }
  status.add("steps since last report", step_count_);
  status.add("mean step time (ms)", 1e3 * mean_step);
  status.add("max step time (ms)", 1e3 * step_time_max_);
  status.add("step period (ms)", 1e3 * health_.step_period);
  status.add("substeps", health_.substeps);
  status.add("iterations (last step)", health_.iterations);
  status.add("max strain", health_.max_strain);
  status.add("structural max strain", health_.structural_max_strain);
  if (health_.target_max_strain > 0.0 || health_.target_penetration > 0.0) {
    status.add("target max strain (solver.target_max_strain)", health_.target_max_strain);
    status.add("target penetration (m, solver.target_penetration)", health_.target_penetration);
    status.add("target met (last step)", health_.target_met ? "yes" : "no");
    status.add("substeps run (last step, every attempt)", health_.substeps_run);
    status.add("budget (solver.max_substeps)", health_.max_substeps);
  }
  status.add("max penetration (m)", health_.max_penetration);
  status.add("degenerate constraints (last step)", health_.degenerate_constraints);
  status.add("truncated self-collision searches (since last report)", truncated_searches_);
  status.add("steps on the calling thread alone (since last report; solver.adaptive_threads)",
             one_thread_steps_);
  status.add("restored steps", health_.restored_steps);
  status.add("last fault", health_.last_fault);
  if (health_.has_cameras) {
    status.add("depth images published", health_.camera_images);
    status.add("depth images dropped (render thread busy)", health_.camera_images_dropped);
    status.add("depth images skipped (no tf for the camera)", health_.camera_images_without_tf);
  }
}

void ClothDiagnostics::inputStatus(diagnostic_updater::DiagnosticStatusWrapper& status) {
  const std::uint32_t total = rejections_->total();
  const std::uint32_t recent = total - rejected_at_last_report_;
  rejected_at_last_report_ = total;
  if (recent > 0) {
    status.summaryf(DiagnosticStatus::WARN, "%u input(s) rejected since the last report; last: %s",
                    recent, rejections_->last().c_str());
  } else {
    status.summary(DiagnosticStatus::OK, "no input rejected since the last report");
  }
  status.add("rejected inputs", total);
  for (const auto& count : rejections_->countsByReason()) {
    status.add(std::string("rejected: ") + toString(count.first), count.second);
  }
  status.add("last rejection", rejections_->last());
}

}  // namespace pbd_cloth
