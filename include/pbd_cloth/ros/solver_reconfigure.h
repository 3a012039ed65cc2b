// The dynamic_reconfigure server of cfg/Solver.cfg (~set_parameters, ~parameter_updates). It
// starts from the values the simulation runs with, hands every change to `apply` and publishes
// what `apply` returns: the values in effect, so a refused value visibly snaps back.
#pragma once

#include <functional>
#include <memory>

#include <ros/node_handle.h>

#include "pbd_cloth/ros/solver_tuning.h"

namespace pbd_cloth {

class SolverReconfigure {
 public:
  // `requested` holds the new values, `groups` the TuningGroup bits that changed. Called on the
  // thread that serves the node handle's callbacks.
  using ApplyCallback = std::function<SolverTuning(const SolverTuning& requested, unsigned groups)>;

  SolverReconfigure(const ros::NodeHandle& nh_private, const SolverTuning& initial,
                    ApplyCallback apply);
  ~SolverReconfigure();

  SolverReconfigure(const SolverReconfigure&) = delete;
  SolverReconfigure& operator=(const SolverReconfigure&) = delete;

  // Publishes values changed by someone else (e.g. a reset that reloaded the scene).
  void publish(const SolverTuning& tuning);

 private:
  // Holds the generated pbd_cloth::SolverConfig, which must stay out of this header (see
  // solver_tuning.h).
  struct Server;
  std::unique_ptr<Server> server_;
};

}  // namespace pbd_cloth
