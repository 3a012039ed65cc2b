// The stretch links' flat, batched projection (stretch_links.h): batches share no particle, the
// grid's links load as whole registers, and the AVX2 path gives the portable loop's result to the
// bit (so a lab's PC without AVX2 simulates exactly what this one does).
#include <gtest/gtest.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <thread>

#include "pbd_cloth/constraints/stretch_links.h"
#include "pbd_cloth/parallel/worker_pool.h"
#include "pbd_cloth/sim/cloth_builder.h"
#include "pbd_cloth/sim/simulation.h"
#include "test_scenes.h"

namespace pbd_cloth {
namespace {

// config/swinging.yaml in small: a flat 20 x 20 cloth with both diagonals swinging from two
// corners; `diagonals` 1 is the default grid.
SceneConfig swingingScene(int diagonals) {
  SceneConfig scene = test::clothScene(20, 20, 0.05, Method::kXpbd);
  scene.cloth.shear_diagonals = diagonals;
  scene.cloth.bend_compliance = -1.0;
  scene.cloth.self_collision = false;
  scene.cloth.stretch_compliance = 0.0;
  scene.cloth.pinned = {0, 19};
  scene.solver.substeps = 10;
  return scene;
}

// One projection of batches [first, end) on positions kept as a Vec3Array: into columns, the
// projection, and back (what Solver::projectStretch does around its sweep).
StretchPassResult projectOn(const StretchLinks& links, int first, int end,
                            const StretchProjection& how, Vec3Array& x, double* lambda) {
  ColumnPositions columns;
  columns.resize(static_cast<int>(x.size()));
  positionsToColumns(x.front().data(), 0, columns.size(), columns.columns(), how.simd);
  const StretchPassResult result =
      projectStretchLinks(links, first, end, how, columns.columns(), lambda);
  positionsFromColumns(columns.columns(), 0, columns.size(), x.front().data(), how.simd);
  return result;
}

// The sweep's paths: the widest this processor has (AVX-512, else AVX2, else the portable loop),
// AVX2 at most, and the portable loop.
struct SweepPath {
  const char* name;
  bool simd;
  bool avx512;
  StretchProjection how() const {
    StretchProjection how;
    how.simd = simd;
    how.avx512 = avx512;
    return how;
  }
};
const SweepPath kSweepPaths[] = {
    {"widest", true, true}, {"AVX2 at most", true, false}, {"portable", false, false}};

StretchLinks linksOf(const SceneConfig& scene) {
  Particles particles;
  ClothTopology topology;
  buildScene(scene, particles, topology);
  StretchLinks links;
  links.assign(topology.stretch, particles.size());
  return links;
}

TEST(StretchLinks, NoTwoLinksOfABatchShareAParticle) {
  for (int diagonals : {1, 2}) {
    const StretchLinks links = linksOf(swingingScene(diagonals));
    ASSERT_GT(links.batchCount(), 0);
    EXPECT_EQ(links.batch_begin.back(), links.size());
    for (int b = 0; b < links.batchCount(); ++b) {
      std::vector<int> ends;
      for (int c = links.batch_begin[b]; c < links.batch_begin[b + 1]; ++c) {
        ends.push_back(links.i[c]);
        ends.push_back(links.j[c]);
      }
      std::sort(ends.begin(), ends.end());
      EXPECT_EQ(std::adjacent_find(ends.begin(), ends.end()), ends.end())
          << "batch " << b << ", diagonals " << diagonals;
    }
  }
}

// The grid's sweep is laid out in runs that step through the particles (cloth_builder.cpp): on
// both 20 x 20 grids at least 75 % of the links go eight to a register (83 %; the rest: the last
// links of each run, fewer than four; on the 50 x 50 benchmark cloth, 95 % go to registers).
TEST(StretchLinks, GridLinksLoadAsWholeRegisters) {
  for (int diagonals : {1, 2}) {
    const StretchLinks links = linksOf(swingingScene(diagonals));
    int in_registers = 0, in_eights = 0;
    for (const StretchLinks::Segment& segment : links.segments) {
      if (segment.layout == StretchLinks::Layout::kScalar) continue;
      in_registers += segment.end - segment.begin;
      if (segment.end - segment.begin == 8) in_eights += 8;
    }
    EXPECT_GE(in_registers, 0.75 * links.size()) << "diagonals " << diagonals;
    EXPECT_GE(in_eights, 0.75 * links.size()) << "diagonals " << diagonals;
    // Segments cover the list in order, each inside its batch.
    int next = 0;
    for (int b = 0; b < links.batchCount(); ++b) {
      for (int g = links.batch_segment[b]; g < links.batch_segment[b + 1]; ++g) {
        EXPECT_EQ(links.segments[g].begin, next);
        next = links.segments[g].end;
        EXPECT_LE(next, links.batch_begin[b + 1]);
      }
    }
    EXPECT_EQ(next, links.size());
  }
}

// Three seconds of swinging, compliant and inextensible, both grids: the AVX2 path (four links
// a register) and the portable loop end in the same positions, bit for bit. The AVX-512 path is
// compared in the next test, which skips (and says so) on a processor without it rather than
// compare AVX2 with itself.
TEST(StretchLinks, Avx2AndPortablePathsAgreeToTheBit) {
  if (!stretchLinksUseAvx2()) GTEST_SKIP() << "no AVX2 here: only the portable path runs";
  for (int diagonals : {1, 2}) {
    for (double compliance : {0.0, 1e-6}) {
      SceneConfig avx2 = swingingScene(diagonals);
      avx2.cloth.stretch_compliance = compliance;
      avx2.solver.levels = compliance == 0.0 ? 3 : 0;
      SceneConfig portable = avx2;
      avx2.solver.avx512 = false;
      portable.solver.simd = false;
      Simulation four(avx2), without(portable);
      const Vec3 corner_start = four.particles().position[399];
      for (int step = 0; step < 180; ++step) {
        four.step();
        without.step();
      }
      EXPECT_EQ(four.particles().position, without.particles().position)
          << "AVX2, diagonals " << diagonals << ", compliance " << compliance;
      // And it moved: a test of two frozen cloths would pass too.
      EXPECT_GT((four.particles().position[399] - corner_start).norm(), 0.2);
    }
  }
}

// The same swings on the AVX-512 path (eight links a register) and the portable loop.
TEST(StretchLinks, Avx512AndPortablePathsAgreeToTheBit) {
  if (!stretchLinksUseAvx512())
    GTEST_SKIP() << "no AVX-512 here: the AVX-512 path cannot run (AVX2 is "
                    "Avx2AndPortablePathsAgreeToTheBit's)";
  for (int diagonals : {1, 2}) {
    for (double compliance : {0.0, 1e-6}) {
      SceneConfig scene = swingingScene(diagonals);
      scene.cloth.stretch_compliance = compliance;
      scene.solver.levels = compliance == 0.0 ? 3 : 0;
      SceneConfig portable = scene;
      portable.solver.simd = false;
      Simulation eight(scene), without(portable);
      const Vec3 corner_start = eight.particles().position[399];
      for (int step = 0; step < 180; ++step) {
        eight.step();
        without.step();
      }
      EXPECT_EQ(eight.particles().position, without.particles().position)
          << "AVX-512, diagonals " << diagonals << ", compliance " << compliance;
      EXPECT_GT((eight.particles().position[399] - corner_start).norm(), 0.2);
    }
  }
}

// Coincident ends inside a register of links (a segment of four, and one of eight: one AVX-512
// register or two AVX2 ones): that register goes link by link, the coincident link is skipped and
// reported by its index, and its neighbours are still projected, on every path.
TEST(StretchLinks, CoincidentEndsInsideARegisterGroupAreReportedByIndex) {
  for (int n : {4, 8}) {
    for (const SweepPath& path : kSweepPaths) {
      std::vector<DistanceConstraint> list;
      for (int k = 0; k < n; ++k) list.push_back({k, k + n, 1.0});  // contiguous: j = i + n
      Vec3Array x(2 * n, Vec3::Zero());
      for (int k = 0; k < n; ++k) {
        x[k] = Vec3(k * 10.0, 0.0, 0.0);
        x[k + n] = Vec3(k * 10.0, 2.0, 0.0);  // every link twice its rest length
      }
      const int coincident = n - 2;
      x[coincident + n] = x[coincident];
      std::vector<double> inverse_mass(2 * n, 1.0);
      StretchLinks links;
      links.assign(list, 2 * n);
      ASSERT_EQ(links.segments.size(), 1u);
      EXPECT_EQ(links.segments[0].layout, StretchLinks::Layout::kContiguous);
      EXPECT_EQ(links.segments[0].end, n);
      links.prepareStep(inverse_mass.data(), 0.0);
      std::vector<double> lambda(n, 0.0);
      const StretchPassResult result =
          projectOn(links, 0, links.batchCount(), path.how(), x, lambda.data());
      EXPECT_EQ(result.degenerate, 1) << path.name << ", " << n;
      EXPECT_EQ(result.first_degenerate, coincident) << path.name << ", " << n;
      EXPECT_EQ(lambda[coincident], 0.0);
      for (int k = 0; k < n; ++k) {
        if (k == coincident) continue;
        EXPECT_NEAR((x[k] - x[k + n]).norm(), 1.0, 1e-12)
            << "link " << k << ", " << path.name << ", " << n;
      }
      EXPECT_NEAR(result.max_change, 0.5, 1e-12);  // each end of a link moved by half its excess
    }
  }
}

// Both diagonals of every other cell of a strip, main then anti per cell (the coarse levels'
// order): i steps by one, j by one swapped in pairs (kCrossed), and the register paths move every
// particle as the link-by-link loop does, to the bit.
TEST(StretchLinks, CrossedDiagonalsLoadAsWholeRegisters) {
  const int cols = 13;  // a 2 x 13 strip: cells 0, 2, ..., 10 of its one row, 12 links
  std::vector<DistanceConstraint> list;
  for (int c = 0; c + 1 < cols; c += 2) {
    list.push_back({c, cols + c + 1, std::sqrt(2.0)});  // main diagonal
    list.push_back({c + 1, cols + c, std::sqrt(2.0)});  // anti-diagonal
  }
  StretchLinks links;
  links.assign(list, 2 * cols);
  ASSERT_EQ(links.batchCount(), 1);
  ASSERT_EQ(links.segments.size(), 2u);  // eight links, then four
  EXPECT_EQ(links.segments[0].end, 8);
  for (const StretchLinks::Segment& segment : links.segments) {
    EXPECT_EQ(segment.layout, StretchLinks::Layout::kCrossed);
  }
  Vec3Array start(2 * cols);
  for (int k = 0; k < 2 * cols; ++k) {
    // Stretched and skewed, differently for every particle.
    start[k] = Vec3(1.3 * (k % cols) + 0.01 * k * k, (k / cols) * 1.7, 0.05 * k);
  }
  std::vector<double> inverse_mass(2 * cols, 1.0);
  inverse_mass[3] = 0.0;  // one kinematic end
  links.prepareStep(inverse_mass.data(), 0.0);
  Vec3Array result[3] = {start, start, start};
  for (int path = 0; path < 3; ++path) {
    std::vector<double> lambda(list.size(), 0.0);
    projectOn(links, 0, 1, kSweepPaths[path].how(), result[path], lambda.data());
  }
  EXPECT_EQ(result[0], result[2]) << kSweepPaths[0].name;
  EXPECT_EQ(result[1], result[2]) << kSweepPaths[1].name;
  EXPECT_EQ(result[2][3], start[3]);
  for (const DistanceConstraint& link : list) {
    EXPECT_NEAR((result[2][link.i] - result[2][link.j]).norm(), link.rest_length, 1e-12);
  }
}

// The copies into and out of columns move every coordinate of [begin, end) exactly, on both paths,
// with the four-at-a-time part and the tail (11 particles from 1 to 10: two groups of four and a
// tail of one), and touch nothing outside the range.
TEST(StretchLinks, ColumnsCopyExactlyTheirRange) {
  for (bool simd : {true, false}) {
    Vec3Array x(11);
    for (int k = 0; k < 11; ++k) x[k] = Vec3(0.1 * k + 1e-13, -3.7 * k, std::sqrt(2.0 + k));
    ColumnPositions columns;
    columns.resize(11);
    const PositionColumns c = columns.columns();
    for (int k = 0; k < 11; ++k) c.x[k] = c.y[k] = c.z[k] = -1.0;
    positionsToColumns(x.front().data(), 1, 10, c, simd);
    for (int k = 0; k < 11; ++k) {
      const bool inside = k >= 1 && k < 10;
      EXPECT_EQ(c.x[k], inside ? x[k][0] : -1.0) << "particle " << k << ", simd " << simd;
      EXPECT_EQ(c.y[k], inside ? x[k][1] : -1.0) << "particle " << k << ", simd " << simd;
      EXPECT_EQ(c.z[k], inside ? x[k][2] : -1.0) << "particle " << k << ", simd " << simd;
    }
    Vec3Array back(11, Vec3::Constant(5.0));
    for (int k = 1; k < 10; ++k) c.y[k] += 1.0;  // so the copy back is seen to carry a change
    positionsFromColumns(c, 1, 10, back.front().data(), simd);
    for (int k = 0; k < 11; ++k) {
      const bool inside = k >= 1 && k < 10;
      EXPECT_EQ(back[k], inside ? Vec3(x[k][0], x[k][1] + 1.0, x[k][2]) : Vec3::Constant(5.0))
          << "particle " << k << ", simd " << simd;
    }
  }
}

// A link with both ends kinematic is skipped: nothing moves and its multiplier stays zero.
TEST(StretchLinks, LinksWithoutAFreeEndAreSkipped) {
  std::vector<DistanceConstraint> list = {{0, 1, 1.0}};
  Vec3Array x = {Vec3::Zero(), Vec3(3.0, 0.0, 0.0)};
  const Vec3Array before = x;
  std::vector<double> inverse_mass = {0.0, 0.0}, lambda = {0.0};
  StretchLinks links;
  links.assign(list, 2);
  links.prepareStep(inverse_mass.data(), 1e-3);
  const StretchPassResult result = projectOn(links, 0, 1, StretchProjection{}, x, lambda.data());
  EXPECT_EQ(x, before);
  EXPECT_EQ(lambda[0], 0.0);
  EXPECT_EQ(result.degenerate, 0);
}

// A substep's first pass starts every multiplier at zero (XPBD, Algorithm 1) by writing it, not by
// a clearing pass: whatever the array held before, the pass ends with the positions and
// multipliers of a pass from a cleared array. Links in registers, link by link (a group with
// coincident ends), without a free end (both ends pinned) and compliant (alpha~ lambda enters the
// step), on both paths; a stale multiplier read instead of zero changes the positions, and one
// left unwritten keeps its garbage.
TEST(StretchLinks, FirstPassWritesTheMultipliersFromZero) {
  for (const SweepPath& path : kSweepPaths) {
    std::vector<DistanceConstraint> list;
    for (int k = 0; k < 4; ++k) list.push_back({k, k + 4, 1.0});   // one register of four
    for (int k = 8; k < 12; ++k) list.push_back({k, k + 4, 1.0});  // four with coincident ends
    list.push_back({16, 17, 1.0});                                 // both ends pinned
    Vec3Array x(18, Vec3::Zero());
    for (int k = 0; k < 16; ++k) x[k] = Vec3((k % 4) * 10.0, (k / 4) * 0.1, 0.0);
    for (int k : {4, 5, 6, 7, 12, 13, 14, 15}) x[k] += Vec3(0.0, 1.5, 0.0);
    x[14] = x[10];  // link 6: coincident ends
    x[17] = Vec3(3.0, 0.0, 0.0);
    std::vector<double> inverse_mass(18, 1.0);
    inverse_mass[16] = inverse_mass[17] = 0.0;
    StretchLinks links;
    links.assign(list, 18);
    links.prepareStep(inverse_mass.data(), 0.5);
    StretchProjection how = path.how();
    how.alpha = 0.5;
    Vec3Array cleared_x = x, stale_x = x;
    std::vector<double> cleared(list.size(), 0.0), stale(list.size(), 7.0);
    projectOn(links, 0, links.batchCount(), how, cleared_x, cleared.data());
    how.lambda_from_zero = true;
    projectOn(links, 0, links.batchCount(), how, stale_x, stale.data());
    EXPECT_EQ(stale_x, cleared_x) << path.name;
    EXPECT_EQ(stale, cleared) << path.name;
    EXPECT_NE(cleared[0], 0.0);  // the links did act
    // Reading the stale 7 instead of zero would have moved the ends differently.
    how.lambda_from_zero = false;
    std::vector<double> read(list.size(), 7.0);
    Vec3Array read_x = x;
    projectOn(links, 0, links.batchCount(), how, read_x, read.data());
    EXPECT_NE(read_x, cleared_x);
  }
}

// What a task's registers load and store (every particle of each window, used or not) is touched
// by no other task of its phase: a window that reached into another task's particles would write
// back values that task may have moved meanwhile (a race that loses its move now and then). Both
// grids, 40 x 40 and 50 x 50 (blocks of 5 and 7 rows); the default grid's single diagonals load
// eight particles and use every other one, and on the 50 x 50 grid such a window reached into
// the next block.
TEST(StretchLinks, RegisterWindowsStayInsideTheirTask) {
  for (int n : {40, 50}) {
    for (int diagonals : {1, 2}) {
      SceneConfig scene = swingingScene(diagonals);
      scene.cloth.rows = scene.cloth.cols = n;
      Particles particles;
      ClothTopology topology;
      buildScene(scene, particles, topology);
      StretchLinks links;
      links.assign(topology.stretch, particles.size(), n, n);
      ASSERT_GT(links.taskCount(), 1);
      int in_registers = 0;  // links
      for (int phase = 0; phase < links.phaseCount(); ++phase) {
        std::vector<int> owner(particles.size(), -1);
        auto claim = [&](int first, int count, int task) {
          for (int q = first; q < first + count; ++q) {
            ASSERT_TRUE(owner[q] == -1 || owner[q] == task)
                << "particle " << q << " in windows of tasks " << owner[q] << " and " << task
                << ", " << n << " x " << n << ", diagonals " << diagonals;
            owner[q] = task;
          }
        };
        for (int t = links.phase_task[phase]; t < links.phase_task[phase + 1]; ++t) {
          for (int g = links.batch_segment[links.task_batch[t]];
               g < links.batch_segment[links.task_batch[t + 1]]; ++g) {
            const StretchLinks::Segment& segment = links.segments[g];
            const int c = segment.begin;
            const int width = segment.end - segment.begin;  // 8 or 4 links to a register
            switch (segment.layout) {
              case StretchLinks::Layout::kScalar:
                for (int k = segment.begin; k < segment.end; ++k) {
                  claim(links.i[k], 1, t);
                  claim(links.j[k], 1, t);
                }
                break;
              case StretchLinks::Layout::kContiguous:
                claim(links.i[c], width, t);
                claim(links.j[c], width, t);
                break;
              case StretchLinks::Layout::kCrossed:
                claim(links.i[c], width, t);
                claim(links.j[c + 1], width, t);
                break;
              case StretchLinks::Layout::kInterleaved:
                claim(links.i[c], 2 * width, t);
                break;
              case StretchLinks::Layout::kStrided:
                claim(links.i[c], 2 * width, t);
                claim(links.j[c], 2 * width, t);
                break;
            }
            if (segment.layout != StretchLinks::Layout::kScalar) in_registers += width;
          }
        }
      }
      // Registers still used.
      EXPECT_GT(in_registers, 0.75 * links.size())
          << n << " x " << n << ", diagonals " << diagonals;
    }
  }
}

// A 40 x 40 grid (eight blocks of five rows) in tasks: every link in exactly one task, each task
// inside one block or one seam, and the tasks of a phase sharing no particle.
TEST(StretchLinks, TasksOfAPhaseShareNoParticle) {
  SceneConfig scene = swingingScene(2);
  scene.cloth.rows = scene.cloth.cols = 40;
  Particles particles;
  ClothTopology topology;
  buildScene(scene, particles, topology);
  StretchLinks links;
  links.assign(topology.stretch, particles.size(), 40, 40);
  ASSERT_EQ(links.phaseCount(), 2);
  EXPECT_EQ(links.taskCount(), 8 + 7);
  std::vector<int> seen(topology.stretch.size(), 0);
  for (int c = 0; c < links.size(); ++c) ++seen[links.original[c]];
  EXPECT_EQ(std::count(seen.begin(), seen.end(), 1), links.size());
  for (int phase = 0; phase < links.phaseCount(); ++phase) {
    std::vector<int> task_of(particles.size(), -1);
    for (int t = links.phase_task[phase]; t < links.phase_task[phase + 1]; ++t) {
      for (int c = links.batch_begin[links.task_batch[t]];
           c < links.batch_begin[links.task_batch[t + 1]]; ++c) {
        for (int end : {links.i[c], links.j[c]}) {
          EXPECT_TRUE(task_of[end] == -1 || task_of[end] == t)
              << "particle " << end << " in tasks " << task_of[end] << " and " << t;
          task_of[end] = t;
        }
      }
    }
  }
}

// solver.threads: 1, 2 and 3 threads step a 40 x 40 cloth with bending, self-collision, a sphere
// and a pinned edge for a second to the same positions, bit for bit.
TEST(StretchLinks, EveryThreadCountGivesTheSameCloth) {
  SceneConfig scene = test::clothScene(40, 40, 0.025, Method::kXpbd);
  scene.cloth.pinned = {0, 39};
  scene.cloth.self_collision = true;
  scene.cloth.bend_compliance = 1e-3;  // hinges in tasks (FlatHinges.HingeTasksOfAGroupShare...)
  scene.solver.substeps = 8;
  // The sphere where the cloth's centre passes after a third of a second, so that its contacts
  // (threaded by particle ranges) act; the same run without it ends elsewhere.
  Vec3 passing = Vec3::Zero();
  {
    Simulation probe(scene);
    for (int step = 0; step < 20; ++step) probe.step();
    for (const Vec3& x : probe.particles().position) passing += x;
    passing /= probe.particles().size();
  }
  const Vec3Array without_sphere = [&] {
    Simulation simulation(scene);
    for (int step = 0; step < 60; ++step) simulation.step();
    return simulation.particles().position;
  }();
  ObstacleConfig sphere;
  sphere.name = "sphere";
  sphere.shape = ShapeType::kSphere;
  sphere.radius = 0.15;
  sphere.pose.position = passing + Vec3(0.0, 0.1, 0.0);
  scene.obstacles = {sphere};
  std::vector<Vec3Array> ends;
  for (int threads : {1, 2, 3}) {
    scene.solver.threads = threads;
    Simulation simulation(scene);
    for (int step = 0; step < 60; ++step) simulation.step();
    ends.push_back(simulation.particles().position);
  }
  EXPECT_EQ(ends[0], ends[1]);
  EXPECT_EQ(ends[0], ends[2]);
  EXPECT_GT((ends[0][1599] - Simulation(scene).particles().position[1599]).norm(), 0.1);
  EXPECT_NE(ends[0], without_sphere);
}

// solver.threads changed between steps (Simulation::setSolverConfig, as a program tuning a running
// simulation would): the cloth is the one of a single thread all along. Before the pool checked
// which job a new worker may take, a worker started after jobs had run took the last one again
// (a freed lambda): WorkerPool.ResizingBetweenRunsRunsEveryIndexOnce crashed there.
TEST(StretchLinks, ThreadsChangedBetweenStepsGiveTheSameCloth) {
  SceneConfig scene = test::clothScene(40, 40, 0.025, Method::kXpbd);
  scene.cloth.pinned = {0, 39};
  scene.solver.substeps = 8;
  Simulation single(scene);
  Simulation changed(scene);
  for (int threads : {2, 3, 1, 2}) {
    SolverConfig solver = changed.scene().solver;
    solver.threads = threads;
    changed.setSolverConfig(solver);
    for (int step = 0; step < 10; ++step) {
      single.step();
      changed.step();
    }
  }
  EXPECT_EQ(changed.particles().position, single.particles().position);
  EXPECT_GT(
      (single.particles().position[1599] - Simulation(scene).particles().position[1599]).norm(),
      0.1);
}

// The pool calls every thread index exactly once per run, and run() returns only when all are
// done, over many quick runs (the solver's pattern: several per substep).
TEST(WorkerPool, EveryIndexRunsOncePerRun) {
  WorkerPool pool;
  pool.resize(3);
  ASSERT_EQ(pool.threads(), 3);
  std::vector<int> calls(3, 0);
  for (int run = 0; run < 20000; ++run) {
    auto job = [&](int t) { ++calls[t]; };
    pool.run(job);
    ASSERT_EQ(calls[0], run + 1);
    ASSERT_EQ(calls[1], run + 1);
    ASSERT_EQ(calls[2], run + 1);
  }
  pool.resize(1);
  EXPECT_EQ(pool.threads(), 1);
  auto job = [&](int t) { ++calls[t]; };
  pool.run(job);
  EXPECT_EQ(calls[0], 20001);
}

// Between runs the workers fall asleep (as they do through a garment's serial self-contacts); the
// caller then claims the indices they have not taken yet. Every index still runs exactly once per
// run, whoever runs it, and run() returns only when all are done.
TEST(WorkerPool, IndicesOfSleepingWorkersRunOnceEach) {
  WorkerPool pool;
  pool.resize(3);
  std::vector<int> calls(3, 0);
  for (int run = 0; run < 200; ++run) {
    // Longer than the workers' spinning (20-50 us): they wait on the condition variable.
    std::this_thread::sleep_for(std::chrono::microseconds(run % 4 == 0 ? 2000 : 50));
    auto job = [&](int t) { ++calls[t]; };
    pool.run(job);
    ASSERT_EQ(calls[0], run + 1);
    ASSERT_EQ(calls[1], run + 1);
    ASSERT_EQ(calls[2], run + 1);
  }
}

// A new thread count between runs (solver.threads changed at run time): the new workers start
// after jobs have run, and must not take an old job for a new one.
TEST(WorkerPool, ResizingBetweenRunsRunsEveryIndexOnce) {
  WorkerPool pool;
  for (int threads : {2, 3, 2, 1, 3, 2}) {
    pool.resize(threads);
    ASSERT_EQ(pool.threads(), threads);
    std::vector<int> calls(threads, 0);
    for (int run = 0; run < 500; ++run) {
      auto job = [&](int t) { ++calls[t]; };
      pool.run(job);
    }
    for (int t = 0; t < threads; ++t)
      EXPECT_EQ(calls[t], 500) << threads << " threads, index " << t;
  }
}

}  // namespace
}  // namespace pbd_cloth
