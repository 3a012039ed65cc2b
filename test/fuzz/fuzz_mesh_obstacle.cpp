// A mesh obstacle file of any content through assimp and our checks (STL, OBJ, PLY, chosen by the
// first byte): a mesh that loads is then collided with a small cloth dropped on it.
#include "fuzz_helpers.h"
#include "pbd_cloth/scene/scene_assets.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size == 0) return 0;
  static const char* const kExtensions[] = {"stl", "obj", "ply"};
  pbd_cloth::SceneConfig scene;
  pbd_cloth::ObstacleConfig mesh;
  mesh.name = "mesh";
  mesh.shape = pbd_cloth::ShapeType::kMesh;
  mesh.mesh = pbd_cloth::fuzz::writeFile(data + 1, size - 1, kExtensions[data[0] % 3]);
  scene.obstacles.push_back(mesh);
  scene.cloth.rows = scene.cloth.cols = 6;
  try {
    pbd_cloth::loadObstacleMeshes(scene);
    pbd_cloth::validate(scene);
  } catch (const pbd_cloth::ConfigError&) {
    return 0;
  }
  pbd_cloth::fuzz::buildAndStep(scene);
  return 0;
}
