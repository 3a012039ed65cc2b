// The set_state path (cloth_bench --load-state, ~set_state after message conversion): any bytes
// as a state file are refused with a reason or fit the scene (a 6 x 6 cloth with a gripper and a
// sphere: state_scene.yaml); a state that fits is set and stepped, and then every position must be
// finite (setState refuses non-finite values).
#include <cmath>
#include <sstream>

#include "fuzz_helpers.h"
#include "pbd_cloth/scene/scene_yaml.h"
#include "pbd_cloth/state/saved_state.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  // test/fuzz/state_scene.yaml, found from this file's path (the fuzzers run from anywhere).
  static const pbd_cloth::SceneConfig scene = pbd_cloth::loadScene(
      std::string(__FILE__).substr(0, std::string(__FILE__).rfind('/')) + "/state_scene.yaml");
  std::istringstream in(pbd_cloth::fuzz::text(data, size));
  pbd_cloth::SimulationState state;
  std::string reason;
  if (!pbd_cloth::readState(in, state, reason)) return 0;
  pbd_cloth::Simulation sim(scene);
  if (!sim.setState(state, reason)) return 0;
  sim.step();
  return 0;
}
