// A robot description of any content: urdfdom's parser and our reading of its collision elements
// (ConfigError naming the link or the parameter), then the robot built beside a small cloth and
// stepped.
#include "fuzz_helpers.h"
#include "pbd_cloth/scene/scene_assets.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  pbd_cloth::SceneConfig scene;
  scene.robot.enabled = true;
  scene.cloth.rows = scene.cloth.cols = 6;
  try {
    pbd_cloth::loadRobot(scene, pbd_cloth::fuzz::text(data, size), "fuzz input");
    pbd_cloth::validate(scene);
  } catch (const pbd_cloth::ConfigError&) {
    return 0;
  }
  pbd_cloth::fuzz::buildAndStep(scene);
  return 0;
}
