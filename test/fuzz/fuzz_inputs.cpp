// Live inputs as the node hands them to the simulation: gripper, obstacle and robot link poses
// (any doubles, NaN and infinities included), grasps and releases, in any order between steps.
// A non-finite pose is refused by the simulation (the node counts it); whatever arrives, the
// state stays finite.
#include <cmath>
#include <cstring>

#include "fuzz_helpers.h"

namespace {

double take(const std::uint8_t*& data, std::size_t& size) {
  double value = 0.0;
  if (size >= sizeof(double)) {
    std::memcpy(&value, data, sizeof(double));
    data += sizeof(double);
    size -= sizeof(double);
  }
  return value;
}

pbd_cloth::Pose takePose(const std::uint8_t*& data, std::size_t& size) {
  pbd_cloth::Pose pose;
  pose.position = Eigen::Vector3d(take(data, size), take(data, size), take(data, size));
  pose.orientation =
      Eigen::Quaterniond(take(data, size), take(data, size), take(data, size), take(data, size));
  return pose;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  static const pbd_cloth::SceneConfig scene = [] {
    pbd_cloth::SceneConfig s;
    s.cloth.rows = s.cloth.cols = 6;
    s.cloth.spacing = 0.05;
    s.cloth.pinned = {0, 5};
    pbd_cloth::GripperConfig gripper;
    gripper.name = "hand";
    gripper.radius = 0.1;
    s.grippers.push_back(gripper);
    pbd_cloth::ObstacleConfig ball;
    ball.name = "ball";
    s.obstacles.push_back(ball);
    pbd_cloth::validate(s);
    return s;
  }();
  pbd_cloth::Simulation sim(scene);
  int steps = 0;
  while (size > 0 && steps < 20) {
    const std::uint8_t op = *data++;
    --size;
    switch (op % 5) {
      case 0:
        sim.setGripperPose(0, takePose(data, size));
        break;
      case 1:
        sim.setObstaclePose(0, takePose(data, size));
        break;
      case 2:
        sim.setGrasp(0, true);
        break;
      case 3:
        sim.setGrasp(0, false);
        break;
      default:
        sim.step();
        ++steps;
    }
  }
  sim.step();
  for (const pbd_cloth::Vec3& x : sim.particles().position) {
    if (!x.allFinite()) __builtin_trap();  // a pose let NaN into the state
  }
  return 0;
}
