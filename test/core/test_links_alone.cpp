// A step of links alone (Solver::linksAlone: nothing in a pass but the flat stretch links and the
// coarse levels, collisions that touch no particle) keeps the particles' positions, velocities
// and substep starts in columns for the whole step instead of copying the positions into columns
// and back around every sweep. It must compute what the passes in place compute, to the bit: the
// same scene with bounds that the cloth never reaches (collisions that do read the particles)
// runs in place and is the reference.
#include <gtest/gtest.h>

#include <string>

#include "pbd_cloth/sim/simulation.h"
#include "test_scenes.h"

namespace pbd_cloth {
namespace {

struct Variant {
  Method method;
  int levels;
  int threads;
  int iterations;
};

std::string describe(const Variant& v) {
  return "method " + std::to_string(static_cast<int>(v.method)) + ", levels " +
         std::to_string(v.levels) + ", threads " + std::to_string(v.threads) + ", iterations " +
         std::to_string(v.iterations);
}

// A 24 x 24 cloth pinned at the two corners of its first row, flat: it swings down as
// config/swinging.yaml does.
SceneConfig swingingScene(const Variant& v) {
  SceneConfig scene = test::clothScene(24, 24, 0.04, v.method);
  scene.cloth.mass = 0.3;
  scene.cloth.pinned = {0, 23};
  scene.solver.substeps = 6;
  scene.solver.iterations = v.iterations;
  scene.solver.levels = v.levels;
  scene.solver.threads = v.threads;
  return scene;
}

TEST(LinksAlone, ColumnsGiveTheBitsOfThePassesInPlace) {
  const Variant variants[] = {{Method::kXpbd, 0, 1, 1}, {Method::kXpbd, 3, 1, 1},
                              {Method::kXpbd, 3, 2, 1}, {Method::kXpbd, 3, 1, 3},
                              {Method::kPbd, 0, 1, 2},  {Method::kVerlet, 2, 2, 2}};
  for (const Variant& v : variants) {
    SceneConfig scene = swingingScene(v);
    Simulation columns(scene);
    scene.bounds.enabled = true;  // 10 m away on every side: never reached, but read every pass
    Simulation in_place(scene);
    const Vec3 corner = columns.particles().position[24 * 24 - 1];
    for (int k = 0; k < 40; ++k) {
      columns.step();
      in_place.step();
      ASSERT_TRUE(columns.solver().stats().links_in_columns) << describe(v);
      ASSERT_FALSE(in_place.solver().stats().links_in_columns) << describe(v);
    }
    // It swung: the free corner fell (the comparison below is not of a cloth at rest).
    EXPECT_GT((columns.particles().position[24 * 24 - 1] - corner).norm(), 0.3) << describe(v);
    EXPECT_EQ(columns.particles().position, in_place.particles().position) << describe(v);
    EXPECT_EQ(columns.particles().velocity, in_place.particles().velocity) << describe(v);
    EXPECT_EQ(columns.particles().substep_start, in_place.particles().substep_start) << describe(v);
    // The pins' reactions are read from the columns too.
    EXPECT_EQ(columns.solver().supportForce(), in_place.solver().supportForce()) << describe(v);
    double support = 0.0;
    for (const Vec3& f : columns.solver().supportForce()) support += f.norm();
    EXPECT_GT(support, 0.1) << describe(v);
  }
}

// A scene whose passes hold more than links (bending here) keeps every pass in place.
TEST(LinksAlone, OnlyWhereAPassHoldsNothingElse) {
  SceneConfig scene = swingingScene({Method::kXpbd, 3, 1, 1});
  scene.cloth.bend_compliance = 1e-3;
  Simulation bending(scene);
  bending.step();
  EXPECT_FALSE(bending.solver().stats().links_in_columns);
  scene.cloth.bend_compliance = -1.0;
  scene.cloth.tethers = true;
  Simulation tethered(scene);
  tethered.step();
  EXPECT_FALSE(tethered.solver().stats().links_in_columns);
}

}  // namespace
}  // namespace pbd_cloth
