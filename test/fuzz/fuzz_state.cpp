// The set_state path (cloth_bench --load-state, ~set_state after message conversion): any bytes
// as a state file are refused with a reason or fit the scene (a 6 x 6 cloth with a gripper and a
// sphere); a state that fits is set and stepped, and then every position must be finite (setState
// refuses non-finite values).
#include <cmath>
#include <sstream>

#include "fuzz_helpers.h"
#include "pbd_cloth/sim_state.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  static const pbd_cloth::SceneConfig scene = [] {
    pbd_cloth::SceneConfig s;
    s.cloth.rows = s.cloth.cols = 6;
    s.cloth.self_collision = true;
    pbd_cloth::GripperConfig gripper;
    gripper.name = "hand";
    s.grippers.push_back(gripper);
    pbd_cloth::ObstacleConfig ball;
    ball.name = "ball";
    s.obstacles.push_back(ball);
    pbd_cloth::validate(s);
    return s;
  }();
  std::istringstream in(pbd_cloth::fuzz::text(data, size));
  pbd_cloth::SimulationState state;
  std::string reason;
  if (!pbd_cloth::readState(in, state, reason)) return 0;
  pbd_cloth::Simulation sim(scene);
  if (!sim.setState(state, reason)) return 0;
  sim.step();
  return 0;
}
