// Small scenes built in code for the core tests (the YAML reader has tests of its own).
#pragma once

#include "pbd_cloth/config/scene_config.h"

namespace pbd_cloth {
namespace test {

// A rows x cols cloth with no bending, no self-collision, one substep and one pass.
inline SceneConfig clothScene(int rows, int cols, double spacing, Method method) {
  SceneConfig scene;
  scene.step_rate = 60.0;
  scene.publish_rate = 30.0;
  scene.solver.method = method;
  scene.solver.substeps = 1;
  scene.solver.iterations = 1;
  scene.cloth.rows = rows;
  scene.cloth.cols = cols;
  scene.cloth.spacing = spacing;
  scene.cloth.mass = rows * cols * 1.0;  // 1 kg per particle
  scene.cloth.origin = Eigen::Vector3d(0.0, 0.0, 0.0);
  scene.cloth.bend_compliance = -1.0;
  scene.cloth.self_collision = false;
  scene.cloth.pinned.clear();
  return scene;
}

}  // namespace test
}  // namespace pbd_cloth
