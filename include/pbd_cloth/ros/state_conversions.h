// The saved simulation state (saved_state.h) <-> pbd_cloth/SimState, for ~get_state and
// ~set_state. Exact: doubles are copied as they are and quaternions are not normalised, so a state
// given back continues bit for bit.
#pragma once

#include <string>

#include "pbd_cloth/SimState.h"
#include "pbd_cloth/state/saved_state.h"

namespace pbd_cloth {

class StateConversions {
 public:
  // The header is the caller's.
  static void toMessage(const SimulationState& state, SimState& msg);
  // False with the reason when solver_data cannot be read; whether the state fits the scene is
  // Simulation::setState's question.
  static bool fromMessage(const SimState& msg, SimulationState& state, std::string& reason);
};

}  // namespace pbd_cloth
