// The scene YAML reader on any text: a valid scene (then built and stepped) or a ConfigError
// naming the key. Mesh and URDF paths the text names are read too (a path into the seed corpus
// directory is how the fuzzer reaches the loaders from YAML).
#include <yaml-cpp/yaml.h>

#include "fuzz_helpers.h"
#include "pbd_cloth/scene/scene_yaml.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  YAML::Node root;
  try {
    root = YAML::Load(pbd_cloth::fuzz::text(data, size));
  } catch (const YAML::Exception&) {
    return 0;  // not YAML: loadSceneYaml turns this into ConfigError("file", ...)
  }
  pbd_cloth::SceneConfig scene;
  try {
    scene = pbd_cloth::sceneFromYaml(root, "/nonexistent");
  } catch (const pbd_cloth::ConfigError&) {
    return 0;
  }
  pbd_cloth::fuzz::buildAndStep(scene);
  return 0;
}
