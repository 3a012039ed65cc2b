// An OBJ cloth (cloth.mesh) of any content: loaded with its checks (ConfigError naming the file
// and the face or vertex, or warnings), then built and stepped, self-collision on.
#include "fuzz_helpers.h"
#include "pbd_cloth/scene/scene_assets.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  pbd_cloth::SceneConfig scene;
  scene.cloth.mesh = pbd_cloth::fuzz::writeFile(data, size, "obj");
  scene.cloth.self_collision = true;
  scene.cloth.tethers = true;
  scene.cloth.pinned = {0};
  try {
    pbd_cloth::loadClothMesh(scene);
    pbd_cloth::validate(scene);
  } catch (const pbd_cloth::ConfigError&) {
    return 0;
  }
  pbd_cloth::fuzz::buildAndStep(scene);
  return 0;
}
