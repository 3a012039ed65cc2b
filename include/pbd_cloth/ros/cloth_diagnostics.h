// The node's diagnostics on /diagnostics (diagnostic_updater), two statuses named after the node:
//   "<node>: simulation"  step time, real-time factor, solver figures; WARN when the node cannot
//                         keep real time (under /use_sim_time: cannot keep up with /clock; as
//                         the clock, ~publish_clock: never), ERROR when the state is no longer
//                         finite or a step was undone since the previous report (fault);
//   "<node>: inputs"      rejected inputs, total and by reason, and the latest one; WARN when some
//                         were rejected since the previous report.
#pragma once

#include <cstdint>
#include <string>

#include <diagnostic_updater/diagnostic_updater.h>
#include <ros/node_handle.h>

#include "pbd_cloth/ros/input_rejections.h"

namespace pbd_cloth {

// What the simulated time follows, for the "keeps up" verdict.
enum class TimeSource {
  kWallClock,  // ROS time is the wall clock: the node must keep real time
  kRosClock,   // /use_sim_time: the node must keep up with /clock, whatever its speed
  kOwnClock,   // ~publish_clock: the node is the clock and cannot fall behind it
};

// What the simulation status reports, taken from the simulation at report time.
struct SimulationHealth {
  TimeSource time_source = TimeSource::kWallClock;
  // kRosClock: simulated s per s of /clock over the last second of it; below 1 the node falls
  // behind /clock (and skips ahead, step_clock.h).
  double clock_factor = 0.0;
  bool clock_factor_valid = false;
  double sim_time = 0.0;                // s
  double step_period = 0.0;             // s, 1 / step_rate
  double real_time_factor = 0.0;        // simulated s per wall s
  bool real_time_factor_valid = false;  // the factor spans enough wall time to judge by
  int substeps = 0;
  int iterations = 0;
  double max_strain = 0.0;
  double max_penetration = 0.0;    // m
  int degenerate_constraints = 0;  // skipped in the last step (coincident particles)
  // Accuracy on demand (the last step): the targets (0: none), what was reached, whether the
  // budget (solver.max_substeps) could not meet them.
  double target_max_strain = 0.0;
  double target_penetration = 0.0;
  double structural_max_strain = 0.0;
  bool target_met = true;
  bool target_budget_exhausted = false;
  int max_substeps = 0;
  int substeps_run = 0;
  bool finite = true;
  // Steps undone by fault recovery since start, and the latest one's fault (Simulation).
  std::uint64_t restored_steps = 0;
  std::string last_fault;
  // Depth cameras (depth_cameras.h), counts since start: images published, dropped because the
  // render thread was still busy, skipped because tf lacked the camera's frame.
  bool has_cameras = false;
  std::uint64_t camera_images = 0;
  std::uint64_t camera_images_dropped = 0;
  std::uint64_t camera_images_without_tf = 0;
};

class ClothDiagnostics {
 public:
  struct Config {
    // Below this real-time factor the node "cannot keep real time" (WARN). Timer jitter alone
    // costs a few percent on a loaded machine, so not 1.0.
    double min_real_time_factor = 0.9;
  };

  // `node_name` prefixes the status names: the private namespace, so a nodelet reports under its
  // own name rather than its manager's.
  ClothDiagnostics(const ros::NodeHandle& nh, const ros::NodeHandle& nh_private,
                   const std::string& node_name, const Config& config);

  // Every step: its wall time (s), its self-collision searches that stopped at their candidate
  // budget (a cloth crushed into itself; SelfCollision::kPairsPerElement), and whether it ran on
  // the calling thread alone although solver.threads > 1 (solver.adaptive_threads found that
  // faster: another process holds a core; thread_choice.h).
  void addStep(double step_wall_time, int truncated_searches, bool on_one_thread = false);
  // Publishes both statuses now; the step figures gathered since the previous report are reset
  // (a crush shorter than the report period still shows).
  void report(const SimulationHealth& health, const InputRejections& rejections);
  // s between reports (the updater's ~diagnostic_period, 1 s by default).
  double period() { return updater_.getPeriod(); }

 private:
  void simulationStatus(diagnostic_updater::DiagnosticStatusWrapper& status);
  void inputStatus(diagnostic_updater::DiagnosticStatusWrapper& status);

  Config config_;
  diagnostic_updater::Updater updater_;
  // Read by the status callbacks during report().
  SimulationHealth health_;
  const InputRejections* rejections_ = nullptr;
  std::uint64_t restored_at_last_report_ = 0;
  // Step wall times and truncated self-collision searches since the previous report.
  int step_count_ = 0;
  double step_time_sum_ = 0.0;
  double step_time_max_ = 0.0;
  int truncated_searches_ = 0;
  int one_thread_steps_ = 0;
  std::uint32_t rejected_at_last_report_ = 0;
};

}  // namespace pbd_cloth
