// The flat hinges' projection (flat_hinges.h): the AVX2 path gives the portable loop's result to
// the bit, in a whole simulation and at the end of the particle array, and one projection solves
// the linear constraint C = scale b exactly (zero compliance).
#include <gtest/gtest.h>

#include <cmath>
#include <utility>
#include <vector>

#include "pbd_cloth/constraints/flat_hinges.h"
#include "pbd_cloth/constraints/stretch_links.h"
#include "pbd_cloth/sim/simulation.h"
#include "test_scenes.h"

namespace pbd_cloth {
namespace {

// A 20 x 20 cloth with bending swinging from two corners for 3 s, twice: the AVX2 path and the
// portable loop end in the same positions, bit for bit. The AVX-512VL path is compared in the
// next test, which skips (and says so) on a processor without it rather than compare AVX2 with
// itself.
SceneConfig swingingHingesScene(double bend_compliance) {
  SceneConfig scene = test::clothScene(20, 20, 0.05, Method::kXpbd);
  scene.cloth.bend_compliance = bend_compliance;
  scene.cloth.self_collision = false;
  scene.cloth.pinned = {0, 19};
  return scene;
}

TEST(FlatHinges, Avx2AndPortablePathsAgreeToTheBit) {
  if (!stretchLinksUseAvx2()) GTEST_SKIP() << "no AVX2 here: only the portable path runs";
  for (double bend_compliance : {0.0, 1e-3}) {
    SceneConfig portable = swingingHingesScene(bend_compliance), avx2 = portable;
    portable.solver.simd = false;
    avx2.solver.avx512 = false;
    Simulation with_avx2(avx2), without(portable);
    ASSERT_GT(with_avx2.topology().bend.size(), 0u);
    const Vec3 corner_start = with_avx2.particles().position[399];
    for (int step = 0; step < 180; ++step) {
      with_avx2.step();
      without.step();
    }
    EXPECT_EQ(with_avx2.particles().position, without.particles().position)
        << "bend compliance " << bend_compliance;
    EXPECT_GT((with_avx2.particles().position[399] - corner_start).norm(), 0.2);
  }
}

// The same swing on the AVX-512VL path and the portable loop: the same positions, bit for bit.
TEST(FlatHinges, Avx512AndPortablePathsAgreeToTheBit) {
  if (!flatHingesUseAvx512Vl())
    GTEST_SKIP() << "no AVX-512VL here: the AVX-512 path cannot run (AVX2 is "
                    "Avx2AndPortablePathsAgreeToTheBit's)";
  for (double bend_compliance : {0.0, 1e-3}) {
    SceneConfig scene = swingingHingesScene(bend_compliance), portable = scene;
    portable.solver.simd = false;
    Simulation with_avx512(scene), without(portable);
    ASSERT_GT(with_avx512.topology().bend.size(), 0u);
    const Vec3 corner_start = with_avx512.particles().position[399];
    for (int step = 0; step < 180; ++step) {
      with_avx512.step();
      without.step();
    }
    EXPECT_EQ(with_avx512.particles().position, without.particles().position)
        << "bend compliance " << bend_compliance;
    EXPECT_GT((with_avx512.particles().position[399] - corner_start).norm(), 0.2);
  }
}

// Threads (solver.threads) take the hinges task by task (cloth_builder.cpp, groupHingesIntoTasks):
// on 50 x 50 and 33 x 40 grids every hinge is in exactly one task, the tasks of each group (the
// row blocks, then the seams) share no particle, and each group has a task for each of two
// threads; a 31-row grid keeps one sequence. The same positions for every thread count are
// StretchLinks.EveryThreadCountGivesTheSameCloth's.
TEST(FlatHinges, HingeTasksOfAGroupShareNoParticle) {
  for (const auto& [rows, cols] : {std::make_pair(50, 50), std::make_pair(33, 40)}) {
    SceneConfig scene = test::clothScene(rows, cols, 0.02, Method::kXpbd);
    scene.cloth.bend_compliance = 1.0;
    scene.cloth.self_collision = false;
    Simulation sim(scene);
    const ClothTopology& topology = sim.topology();
    const std::vector<int>& task = topology.bend_task;
    ASSERT_FALSE(task.empty()) << rows << " x " << cols;
    const int tasks = static_cast<int>(task.size()) - 1;
    const int blocks = topology.bend_blocks;
    EXPECT_EQ(tasks, 2 * blocks - 1);
    EXPECT_GE(blocks, 2);
    EXPECT_EQ(task.front(), 0);
    EXPECT_EQ(task.back(), static_cast<int>(topology.bend.size()));
    for (const auto& [first, end] : {std::make_pair(0, blocks), std::make_pair(blocks, tasks)}) {
      std::vector<int> owner(rows * cols, -1);  // the task of the group that touched a particle
      for (int t = first; t < end; ++t) {
        EXPECT_LT(task[t], task[t + 1]) << "task " << t << " is empty";
        for (int c = task[t]; c < task[t + 1]; ++c) {
          for (int k = 0; k < 4; ++k) {
            const int i = topology.bend[c].index[k];
            EXPECT_TRUE(owner[i] == -1 || owner[i] == t)
                << "particle " << i << " in tasks " << owner[i] << " and " << t;
            owner[i] = t;
          }
        }
      }
    }
  }
  SceneConfig small = test::clothScene(31, 31, 0.02, Method::kXpbd);
  small.cloth.bend_compliance = 1.0;
  EXPECT_TRUE(Simulation(small).topology().bend_task.empty());
}

// One hinge whose corners are the last particles of the array (the AVX2 path reads and writes x y
// z only), bent out of plane: one projection at zero compliance leaves b = 0 (the constraint is
// linear in the positions), on both paths alike, and the particle before them is untouched.
TEST(FlatHinges, OneProjectionFlattensAHingeAtTheEndOfTheArray) {
  BendConstraint hinge;
  hinge.index[0] = 1;
  hinge.index[1] = 2;
  hinge.index[2] = 3;
  hinge.index[3] = 4;
  // Any K with sum zero is a flat hinge's constraint; these are not symmetric, so a path that
  // mixed up the corners would show.
  hinge.weight[1] = 0.5;
  hinge.weight[2] = -1.0;
  hinge.weight[3] = 1.25;
  hinge.weight[0] = -(hinge.weight[1] + hinge.weight[2] + hinge.weight[3]);
  hinge.scale = 1.5;
  const std::vector<double> start = {9.0, 9.0, 9.0, 0.0, 0.0, 0.0,  1.0, 0.0,
                                     0.0, 0.5, 1.0, 0.3, 0.5, -1.0, -0.2};
  const double inverse_mass[4] = {1.0, 2.0, 1.0, 0.5};
  // What Solver::prepareBendStep fixes, at zero compliance (XPBD, k = 1): flat_hinges.h.
  FlatHinge step;
  double w = 0.0;
  for (int v = 0; v < 4; ++v) {
    step.index[v] = hinge.index[v];
    step.move[v] = inverse_mass[v] * hinge.weight[v] * hinge.scale;
    w += inverse_mass[v] * hinge.weight[v] * hinge.weight[v];
    step.largest_move = std::max(step.largest_move, std::abs(step.move[v]));
  }
  w *= hinge.scale * hinge.scale;
  for (int v = 0; v < 3; ++v) step.gain[v] = -hinge.scale * hinge.weight[v + 1] / w;
  // The three paths: portable, AVX2, AVX-512VL (each where this processor has it).
  std::vector<double> result[3];
  for (int path = 0; path < 3; ++path) {
    const bool simd = path > 0, avx512 = path == 2;
    std::vector<double> x = start, lambda(3, 0.0);
    const double moved =
        projectFlatHinges(&step, 1, false, true, true, simd, avx512, x.data(), lambda.data());
    EXPECT_GT(moved, 0.01);
    for (int d = 0; d < 3; ++d) {
      double b = 0.0;
      for (int v = 0; v < 4; ++v) b += hinge.weight[v] * x[3 * hinge.index[v] + d];
      EXPECT_NEAR(b, 0.0, 1e-12) << "coordinate " << d << ", path " << path;
      EXPECT_EQ(x[d], 9.0);  // particle 0 is no corner
    }
    // The largest move it reports is the largest corner's.
    double largest = 0.0;
    for (int i = 1; i <= 4; ++i) {
      double sq = 0.0;
      for (int d = 0; d < 3; ++d)
        sq += (x[3 * i + d] - start[3 * i + d]) * (x[3 * i + d] - start[3 * i + d]);
      largest = std::max(largest, std::sqrt(sq));
    }
    EXPECT_NEAR(moved, largest, 1e-12 * largest) << "path " << path;
    // Untracked, and with the multipliers written instead of read (a substep's first pass, over
    // a stale value): the same positions and multipliers, and no change reported.
    std::vector<double> untracked = start, untracked_lambda(3, 7.0);
    EXPECT_EQ(projectFlatHinges(&step, 1, true, true, false, simd, avx512, untracked.data(),
                                untracked_lambda.data()),
              0.0);
    EXPECT_EQ(untracked, x);
    EXPECT_EQ(untracked_lambda, lambda);
    // A substep's last pass (keep_multipliers false), first or later: the same positions, and the
    // multiplier written only by a hinge with a kinematic reaction to give.
    for (bool reaction : {false, true}) {
      for (bool from_zero : {true, false}) {
        FlatHinge last = step;
        last.reaction = reaction;
        std::vector<double> last_x = start, last_lambda(3, from_zero ? 7.0 : 0.0);
        projectFlatHinges(&last, 1, from_zero, false, false, simd, avx512, last_x.data(),
                          last_lambda.data());
        EXPECT_EQ(last_x, x) << "path " << path;
        EXPECT_EQ(last_lambda, reaction ? lambda : std::vector<double>(3, from_zero ? 7.0 : 0.0))
            << "path " << path << ", reaction " << reaction << ", from zero " << from_zero;
      }
    }
    result[path] = x;
  }
  EXPECT_EQ(result[0], result[1]);
  EXPECT_EQ(result[0], result[2]);
}

// A rope (one row: no triangles, no hinges) with bending on steps on both paths: no hinge to
// project and no multiplier to point at (the sanitizer build checks that nothing reads one).
// The substep's last pass writes the multipliers only of hinges marked `reaction`, so the mark
// must be on every hinge the kinematic reactions read (Solver::startReactions: a corner
// kinematic, another free) and on no other: on a 12 x 12 cloth with its two top corners pinned
// and one particle between them grasped (inverse mass 0), each hinge's mark is what its corners
// say, the marked ones include hinges of all three, and a hinge of only kinematic corners (none
// free: skipped) is not marked.
TEST(FlatHinges, ReactionMarksTheHingesWithKinematicAndFreeCorners) {
  SceneConfig scene = test::clothScene(12, 12, 0.05, Method::kXpbd);
  scene.cloth.bend_compliance = 1e-4;
  scene.cloth.self_collision = false;
  scene.cloth.pinned = {0, 11};
  Simulation sim(scene);
  std::vector<double> inverse_mass = sim.particles().inverse_mass;
  inverse_mass[5] = 0.0;
  const auto& bend = sim.topology().bend;
  ASSERT_GT(bend.size(), 100u);
  int marked = 0;
  bool marks[3] = {false, false, false};  // corners 0, 11 and 5
  for (const BendConstraint& con : bend) {
    const FlatHinge hinge = makeFlatHinge(con, inverse_mass.data(), 1e-2, 1.0, 1e-300);
    int kinematic = 0;
    for (int v = 0; v < 4; ++v) kinematic += inverse_mass[con.index[v]] == 0.0;
    EXPECT_EQ(hinge.reaction, kinematic > 0 && kinematic < 4);
    if (!hinge.reaction) continue;
    ++marked;
    for (int v = 0; v < 4; ++v) {
      marks[0] |= con.index[v] == 0;
      marks[1] |= con.index[v] == 11;
      marks[2] |= con.index[v] == 5;
    }
  }
  EXPECT_GE(marked, 5);
  EXPECT_TRUE(marks[0] && marks[1] && marks[2]);
  BendConstraint all_kinematic = bend.front();
  std::vector<double> none_free(inverse_mass.size(), 0.0);
  EXPECT_FALSE(makeFlatHinge(all_kinematic, none_free.data(), 1e-2, 1.0, 1e-300).reaction);
}

TEST(FlatHinges, AClothWithoutHingesSteps) {
  for (bool simd : {true, false}) {
    SceneConfig scene = test::clothScene(1, 20, 0.05, Method::kXpbd);
    scene.cloth.bend_compliance = 1e-3;
    scene.cloth.self_collision = false;
    scene.cloth.pinned = {0};
    scene.solver.simd = simd;
    Simulation sim(scene);
    ASSERT_TRUE(sim.topology().bend.empty());
    const Vec3 end_start = sim.particles().position[19];
    for (int step = 0; step < 30; ++step) sim.step();
    EXPECT_TRUE(sim.computeMetrics().finite);
    EXPECT_GT((sim.particles().position[19] - end_start).norm(), 0.1) << "simd " << simd;
  }
}

}  // namespace
}  // namespace pbd_cloth
