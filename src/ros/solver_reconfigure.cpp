// Only the generated pbd_cloth::SolverConfig lives here; the core's class of the same name must not
// be included (see solver_tuning.h).
#include "pbd_cloth/ros/solver_reconfigure.h"

#include <dynamic_reconfigure/server.h>
#include <boost/thread/recursive_mutex.hpp>

#include "pbd_cloth/SolverConfig.h"

namespace pbd_cloth {
namespace {

using Config = pbd_cloth::SolverConfig;  // the generated one

// Writes the values into `config`, leaving its bookkeeping (groups, state) alone.
void writeInto(const SolverTuning& tuning, Config& config) {
  config.substeps = tuning.substeps;
  config.iterations = tuning.iterations;
  config.tolerance = tuning.tolerance;
  config.ordering = tuning.ordering;
  config.relaxation = tuning.relaxation;
  config.damping = tuning.damping;
  config.target_max_strain = tuning.target_max_strain;
  config.target_penetration = tuning.target_penetration;
  config.min_substeps = tuning.min_substeps;
  config.max_substeps = tuning.max_substeps;
  config.stretch_compliance = tuning.stretch_compliance;
  config.bend_compliance = tuning.bend_compliance;
  config.friction_static = tuning.friction_static;
  config.friction_kinetic = tuning.friction_kinetic;
}

Config toConfig(const SolverTuning& tuning) {
  Config config = Config::__getDefault__();
  writeInto(tuning, config);
  return config;
}

SolverTuning fromConfig(const Config& config) {
  SolverTuning tuning;
  tuning.substeps = config.substeps;
  tuning.iterations = config.iterations;
  tuning.tolerance = config.tolerance;
  tuning.ordering = config.ordering;
  tuning.relaxation = config.relaxation;
  tuning.damping = config.damping;
  tuning.target_max_strain = config.target_max_strain;
  tuning.target_penetration = config.target_penetration;
  tuning.min_substeps = config.min_substeps;
  tuning.max_substeps = config.max_substeps;
  tuning.stretch_compliance = config.stretch_compliance;
  tuning.bend_compliance = config.bend_compliance;
  tuning.friction_static = config.friction_static;
  tuning.friction_kinetic = config.friction_kinetic;
  return tuning;
}

}  // namespace

struct SolverReconfigure::Server {
  explicit Server(const ros::NodeHandle& nh) : server(mutex, nh) {}

  // Declared before the server, which keeps a reference to it.
  boost::recursive_mutex mutex;
  dynamic_reconfigure::Server<Config> server;
};

SolverReconfigure::SolverReconfigure(const ros::NodeHandle& nh_private, const SolverTuning& initial,
                                     ApplyCallback apply)
    : server_(std::make_unique<Server>(nh_private)) {
  // The server starts from Solver.cfg's defaults and whatever an earlier run left on the parameter
  // server; the scene the simulation was built from is what runs, so publish that instead.
  server_->server.updateConfig(toConfig(initial));
  // setCallback calls back at once with every level set; those values are already running.
  bool started = false;
  server_->server.setCallback([apply, started](Config& config, std::uint32_t level) mutable {
    if (!started) {
      started = true;
      return;
    }
    // Written back into `config`: the server publishes it as the values in effect.
    writeInto(apply(fromConfig(config), level), config);
  });
}

SolverReconfigure::~SolverReconfigure() = default;

void SolverReconfigure::publish(const SolverTuning& tuning) {
  server_->server.updateConfig(toConfig(tuning));
}

}  // namespace pbd_cloth
