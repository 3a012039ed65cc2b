// Bending turned on while the simulation runs (setClothCompliance, the node's dynamic_reconfigure
// bend_compliance from negative to >= 0): a scene built with bending off has no hinges, and turning
// it on builds them then, so it acts from the next step exactly as in a scene built with them.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <memory>

#include "pbd_cloth/sim/mesh_cloth.h"
#include "pbd_cloth/sim/simulation.h"
#include "test_scenes.h"

namespace pbd_cloth {
namespace {

constexpr double kBendCompliance = 1e-3;

// A 10 x 10 cloth (0.45 m square) hanging from its two top corners: it sags into folds, where
// bending acts.
SceneConfig gridScene(double bend_compliance) {
  SceneConfig scene = test::clothScene(10, 10, 0.05, Method::kXpbd);
  scene.solver.substeps = 8;
  scene.cloth.mass = 0.1;
  scene.cloth.rpy = Vec3(0.5 * std::acos(-1.0), 0.0, 0.0);  // hangs in the x-z plane
  scene.cloth.origin = Vec3(0.0, 0.0, 1.0);
  scene.cloth.pinned = {0, 9};
  scene.cloth.bend_compliance = bend_compliance;
  return scene;
}

// The same cloth as a mesh, creased 90 degrees along its middle column: its hinges there have a
// curved rest shape (BendRest), the mesh's own rest angle.
SceneConfig creasedMeshScene(double bend_compliance) {
  const int n = 10;
  const double spacing = 0.05;
  auto mesh = std::make_shared<ClothMesh>();
  mesh->source = "creased 10 x 10 sheet";
  for (int r = 0; r < n; ++r) {
    for (int c = 0; c < n; ++c) {
      const double across = (c - (n - 1) / 2.0) * spacing;  // the crease at across = 0
      mesh->vertices.emplace_back(std::min(across, 0.0), -r * spacing, std::max(across, 0.0));
    }
  }
  for (int r = 0; r + 1 < n; ++r) {
    for (int c = 0; c + 1 < n; ++c) {
      const unsigned i = r * n + c;
      for (unsigned v : {i, i + n, i + 1, i + 1, i + n, i + n + 1}) mesh->triangles.push_back(v);
      mesh->triangle_face.push_back(static_cast<int>(mesh->triangle_face.size()) + 1);
      mesh->triangle_face.push_back(static_cast<int>(mesh->triangle_face.size()) + 1);
    }
  }
  SceneConfig scene = gridScene(bend_compliance);
  scene.cloth.mesh = mesh->source;
  scene.cloth.mesh_data = mesh;
  scene.cloth.rpy = Vec3::Zero();
  scene.cloth.pinned = {0, n - 1};
  return scene;
}

double largestDifference(const Simulation& a, const Simulation& b) {
  double largest = 0.0;
  for (int i = 0; i < a.particles().size(); ++i) {
    largest = std::max(largest, (a.particles().position[i] - b.particles().position[i]).norm());
  }
  return largest;
}

// Three runs of 0.5 s with bending off, then 0.5 s with it on: `turned_on` built without hinges,
// `built_with` built with them (switched off, then on again), `never` with bending off throughout.
// The first two end bit for bit alike; the third differs, so bending did act.
void expectBendingActsOnceTurnedOn(SceneConfig (*scene)(double), const char* name) {
  Simulation turned_on(scene(-1.0));
  Simulation built_with(scene(kBendCompliance));
  Simulation never(scene(-1.0));
  ASSERT_TRUE(turned_on.topology().bend.empty()) << name;
  ASSERT_FALSE(built_with.topology().bend.empty()) << name;
  built_with.setClothCompliance(0.0, -1.0);
  for (int k = 0; k < 30; ++k) {
    turned_on.step();
    built_with.step();
    never.step();
  }
  ASSERT_EQ(largestDifference(turned_on, built_with), 0.0) << name << ": bending off in both";

  turned_on.setClothCompliance(0.0, kBendCompliance);
  built_with.setClothCompliance(0.0, kBendCompliance);
  EXPECT_EQ(turned_on.topology().bend.size(), built_with.topology().bend.size()) << name;
  EXPECT_EQ(turned_on.topology().bend_rest.size(), built_with.topology().bend_rest.size()) << name;
  for (int k = 0; k < 30; ++k) {
    turned_on.step();
    built_with.step();
    never.step();
  }
  EXPECT_EQ(largestDifference(turned_on, built_with), 0.0)
      << name << ": turned on live, not as a scene built with bending";
  EXPECT_GT(largestDifference(turned_on, never), 1e-4) << name << ": bending did not act";
  // Kept by a reset: the scene now says bending is on.
  turned_on.reset();
  EXPECT_EQ(turned_on.topology().bend.size(), built_with.topology().bend.size()) << name;
}

TEST(LiveBending, TurnedOnLiveActsAsIfBuiltWithItOnTheGrid) {
  expectBendingActsOnceTurnedOn(gridScene, "grid");
}

TEST(LiveBending, TurnedOnLiveActsAsIfBuiltWithItOnAMeshWithItsRestAngle) {
  expectBendingActsOnceTurnedOn(creasedMeshScene, "creased mesh");
}

}  // namespace
}  // namespace pbd_cloth
